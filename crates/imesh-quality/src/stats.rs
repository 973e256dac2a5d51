//! Summary statistics and histograms of per-element quality values.

use serde::{Deserialize, Serialize};

/// Worst / mean / variance of a set of quality values, and how many fall below a threshold.
///
/// `worst` is the minimum for metrics where larger is better (shape, shape-and-size, scaled
/// Jacobian, minimum angle); use [`Statistics::max`] for the others. The variance is the sample
/// variance (n − 1), as `vtkMeshQuality` reports it.
///
/// In JSON the count below the threshold also has a key naming the threshold, as the report's
/// stable keys have it (DESIGN.md §6): `below_0_2` for a threshold of 0.2, `below_45` for 45.
///
/// ```
/// use imesh_quality::Statistics;
/// let s = Statistics::of(&[1.0, 0.5, 0.1, 0.9], 0.2);
/// assert_eq!((s.min, s.max, s.count, s.below), (0.1, 1.0, 4, 1));
/// assert!((s.mean - 0.625).abs() < 1e-15);
/// let json = serde_json::to_value(s)?;
/// assert_eq!((&json["below_0_2"], &json["below"]), (&1.into(), &1.into()));
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Statistics {
    /// Smallest value (NaN-free input assumed; NaNs are skipped).
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample variance (n − 1); 0 for fewer than two values.
    pub variance: f64,
    /// Number of values.
    pub count: usize,
    /// The threshold used for `below`.
    pub threshold: f64,
    /// Number of values strictly below `threshold`.
    pub below: usize,
}

impl Serialize for Statistics {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(8))?;
        map.serialize_entry("min", &self.min)?;
        map.serialize_entry("max", &self.max)?;
        map.serialize_entry("mean", &self.mean)?;
        map.serialize_entry("variance", &self.variance)?;
        map.serialize_entry("count", &self.count)?;
        map.serialize_entry("threshold", &self.threshold)?;
        map.serialize_entry("below", &self.below)?;
        map.serialize_entry(&self.below_key(), &self.below)?;
        map.end()
    }
}

impl Statistics {
    /// The JSON key naming the count below the threshold: `below_0_2` for 0.2, `below_135` for
    /// 135 (the threshold as Rust prints it, its point an underscore).
    ///
    /// ```
    /// use imesh_quality::Statistics;
    /// assert_eq!(Statistics::of(&[], 0.3).below_key(), "below_0_3");
    /// assert_eq!(Statistics::of(&[], 45.0).below_key(), "below_45");
    /// ```
    pub fn below_key(&self) -> String {
        format!("below_{}", self.threshold).replace(['.', '-'], "_")
    }

    /// Statistics of `values` (NaNs skipped), counting those below `threshold`.
    pub fn of(values: &[f64], threshold: f64) -> Self {
        let mut s = Self {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            mean: 0.0,
            variance: 0.0,
            count: 0,
            threshold,
            below: 0,
        };
        // Welford's update: stable for millions of values near 1.
        let mut m2 = 0.0;
        for &v in values.iter().filter(|v| !v.is_nan()) {
            s.count += 1;
            s.min = s.min.min(v);
            s.max = s.max.max(v);
            s.below += usize::from(v < threshold);
            let delta = v - s.mean;
            s.mean += delta / s.count as f64;
            m2 += delta * (v - s.mean);
        }
        if s.count == 0 {
            s.min = f64::NAN;
            s.max = f64::NAN;
            s.mean = f64::NAN;
        }
        if s.count > 1 {
            s.variance = m2 / (s.count - 1) as f64;
        }
        s
    }
}

/// Counts of values in equal-width bins over `[lo, hi]` (values outside are clamped into the end
/// bins, so every value is counted).
///
/// ```
/// use imesh_quality::Histogram;
/// let h = Histogram::of(&[0.05, 0.5, 0.55, 1.0, 2.0], 0.0, 1.0, 10);
/// assert_eq!(h.counts[0], 1);
/// assert_eq!(h.counts[5], 2);
/// assert_eq!(h.counts[9], 2); // 1.0 and the clamped 2.0
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Upper edge of the last bin.
    pub hi: f64,
    /// Count per bin.
    pub counts: Vec<usize>,
}

impl Histogram {
    /// Histogram of `values` (NaNs skipped) with `bins` equal bins over `[lo, hi]` (at least one
    /// bin; an empty or inverted range puts everything in the first bin).
    pub fn of(values: &[f64], lo: f64, hi: f64, bins: usize) -> Self {
        let bins = bins.max(1);
        let mut counts = vec![0; bins];
        let width = (hi - lo) / bins as f64;
        for &v in values.iter().filter(|v| !v.is_nan()) {
            let i = if width > 0.0 {
                ((v - lo) / width).floor()
            } else {
                0.0
            };
            counts[(i.max(0.0) as usize).min(bins - 1)] += 1;
        }
        Self { lo, hi, counts }
    }

    /// The `[lower, upper)` edges of bin `i`.
    pub fn bin_edges(&self, i: usize) -> (f64, f64) {
        let w = (self.hi - self.lo) / self.counts.len() as f64;
        (self.lo + w * i as f64, self.lo + w * (i + 1) as f64)
    }
}

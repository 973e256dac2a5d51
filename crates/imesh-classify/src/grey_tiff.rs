//! Grey TIFFs whose samples the `image` crate does not decode: signed integers (CT scans in
//! Hounsfield units), 32- and 64-bit integers (label maps of segmentation tools) and floating
//! point (any measured field). Read with the `tiff` crate (the `image` crate's own TIFF
//! backend) and brought to 16-bit grey, the widest grey the rest of the pipeline reads.

use std::io::Cursor;
use std::path::Path;

use image::metadata::Orientation;
use image::{DynamicImage, ImageBuffer};
use rayon::prelude::*;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use crate::ClassifyError;

/// Most distinct values brought to 16 bits one for one.
const GREY_LEVELS: usize = 1 << 16;

/// Whether `bytes` start like a TIFF (classic or BigTIFF, either byte order).
pub(crate) fn is_tiff(bytes: &[u8]) -> bool {
    matches!(
        bytes.get(..4),
        Some(b"II*\0" | b"MM\0*" | b"II+\0" | b"MM\0+")
    )
}

/// The first image of a TIFF of one grey channel, any sample type, as 16-bit grey
/// ([`to_grey16`]); `None` when the TIFF is not one grey channel the `tiff` crate reads (the
/// caller then reports the `image` crate's error). Refuses an image over `max_pixels` before
/// decoding it.
pub(crate) fn decode_grey_tiff(
    bytes: &[u8],
    path: &Path,
    max_pixels: u64,
) -> Option<Result<DynamicImage, ClassifyError>> {
    let mut decoder = Decoder::new(Cursor::new(bytes)).ok()?;
    let (width, height) = decoder.dimensions().ok()?;
    if !matches!(decoder.colortype().ok()?, tiff::ColorType::Gray(_)) {
        return None;
    }
    Some(decode_checked(decoder, path, width, height, max_pixels))
}

fn decode_checked(
    mut decoder: Decoder<Cursor<&[u8]>>,
    path: &Path,
    width: u32,
    height: u32,
    max_pixels: u64,
) -> Result<DynamicImage, ClassifyError> {
    crate::load::check_size(path, width, height, max_pixels)?;
    let failed = |reason: String| ClassifyError::Decode {
        path: path.to_path_buf(),
        reason,
    };
    let mut limits = Limits::default();
    // Eight bytes a pixel: 64-bit samples, the widest there are.
    limits.decoding_buffer_size = usize::try_from(max_pixels.saturating_mul(8))
        .unwrap_or(usize::MAX)
        .max(1 << 20);
    // As the `image` crate reads it for the TIFFs it decodes.
    let orientation = decoder
        .find_tag(Tag::Orientation)
        .ok()
        .flatten()
        .and_then(|v| v.into_u16().ok())
        .and_then(|v| Orientation::from_exif(v.min(255) as u8))
        .unwrap_or(Orientation::NoTransforms);
    let samples = decoder
        .with_limits(limits)
        .read_image()
        .map_err(|e| failed(e.to_string()))?;
    let grey = match &samples {
        DecodingResult::U8(v) => to_grey16(v, f64::from),
        DecodingResult::U16(v) => to_grey16(v, f64::from),
        DecodingResult::U32(v) => to_grey16(v, f64::from),
        DecodingResult::U64(v) => to_grey16(v, |x| x as f64),
        DecodingResult::I8(v) => to_grey16(v, f64::from),
        DecodingResult::I16(v) => to_grey16(v, f64::from),
        DecodingResult::I32(v) => to_grey16(v, f64::from),
        DecodingResult::I64(v) => to_grey16(v, |x| x as f64),
        DecodingResult::F16(v) => to_grey16(v, |x| x.to_f64()),
        DecodingResult::F32(v) => to_grey16(v, f64::from),
        DecodingResult::F64(v) => to_grey16(v, |x| x),
    };
    let mut image = ImageBuffer::from_raw(width, height, grey)
        .map(DynamicImage::ImageLuma16)
        .ok_or_else(|| failed(format!("fewer samples than its {width}×{height} pixels")))?;
    image.apply_orientation(orientation);
    Ok(image)
}

/// Grey values of any type brought to 16 bits, in their order, keeping apart every two that
/// differ wherever 16 bits can:
///
/// - values that are all whole numbers from 0 to 65 535 (a label map's ids, counts) are kept
///   as they are, so that labels keep their numbers;
/// - otherwise the range of the finite values is stretched linearly over 0–65 535 when that
///   keeps every two distinct values apart (a CT scan's −1 024…3 071, a float map with up to
///   65 536 steps);
/// - otherwise, up to 65 536 distinct values are spread over 0–65 535 by rank (labels with
///   ids far apart), and more are stretched linearly (close values then share a level).
///
/// Not-a-number and −∞ samples take level 0, +∞ the top level.
pub(crate) fn to_grey16<T: Copy + Sync>(values: &[T], f: impl Fn(T) -> f64 + Sync) -> Vec<u16> {
    let whole = values.par_iter().all(|&x| {
        let v = f(x);
        v.fract() == 0.0 && (0.0..=65535.0).contains(&v)
    });
    if whole {
        return values.par_iter().map(|&x| f(x) as u16).collect();
    }
    let linear = |lo: f64, hi: f64| {
        let scale = if hi > lo { 65535.0 / (hi - lo) } else { 0.0 };
        move |v: f64| {
            if v.is_nan() {
                0
            } else {
                // Saturating: −∞ → 0, +∞ → 65 535.
                ((v - lo) * scale).round().clamp(0.0, 65535.0) as u16
            }
        }
    };
    let distinct = distinct_finite(values, &f);
    match distinct {
        Some(d) if !d.is_empty() => {
            let (lo, hi) = (d[0], d[d.len() - 1]);
            let gap = d
                .windows(2)
                .map(|w| w[1] - w[0])
                .fold(f64::INFINITY, f64::min);
            // A margin of one level over the exact bound: rounding stays one-to-one.
            if d.len() == 1 || (hi - lo) / gap <= 65534.0 {
                let map = linear(lo, hi);
                values.par_iter().map(|&x| map(f(x))).collect()
            } else {
                let top = (d.len() - 1) as f64;
                values
                    .par_iter()
                    .map(|&x| {
                        let v = f(x);
                        if v.is_nan() {
                            return 0;
                        }
                        // −0.0 is 0.0, as in `distinct_finite`.
                        let v = if v == 0.0 { 0.0 } else { v };
                        match d.binary_search_by(|p| p.total_cmp(&v)) {
                            Ok(r) => (r as f64 * 65535.0 / top).round() as u16,
                            Err(0) => 0,
                            Err(_) => 65535,
                        }
                    })
                    .collect()
            }
        }
        Some(_) => vec![0; values.len()],
        None => {
            let (lo, hi) = crate::depth::finite_range(values.par_iter().map(|&x| f(x)));
            let map = linear(lo, hi);
            values.par_iter().map(|&x| map(f(x))).collect()
        }
    }
}

/// The distinct finite values in increasing order, or `None` when there are more than
/// [`GREY_LEVELS`].
fn distinct_finite<T: Copy + Sync>(
    values: &[T],
    f: &(impl Fn(T) -> f64 + Sync),
) -> Option<Vec<f64>> {
    let mut seen = std::collections::HashSet::new();
    let mut last = None;
    for &x in values {
        let v = f(x);
        // 0.0 and −0.0 are one value.
        let key = if v == 0.0 { 0 } else { v.to_bits() };
        if v.is_finite() && last != Some(key) {
            last = Some(key);
            seen.insert(key);
            if seen.len() > GREY_LEVELS {
                return None;
            }
        }
    }
    let mut d: Vec<f64> = seen.into_iter().map(f64::from_bits).collect();
    d.sort_unstable_by(f64::total_cmp);
    Some(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The order is kept, and distinct values stay apart (there are fewer than 2^16 here).
        #[test]
        fn the_levels_keep_the_order_and_the_differences(
            values in prop::collection::vec(
                prop_oneof![
                    -1e12f64..1e12,
                    (-70_000i64..70_000).prop_map(|v| v as f64),
                    (0u32..8).prop_map(|e| f64::from(10u32.pow(e))),
                ],
                1..300,
            )
        ) {
            let g = to_grey16(&values, |x| x);
            for (i, a) in values.iter().enumerate() {
                for (j, b) in values.iter().enumerate() {
                    if a < b {
                        prop_assert!(g[i] < g[j], "{a} < {b} but levels {} and {}", g[i], g[j]);
                    } else if a == b {
                        prop_assert_eq!(g[i], g[j]);
                    }
                }
            }
        }
    }

    #[test]
    fn whole_values_within_16_bits_keep_their_numbers() {
        assert_eq!(to_grey16(&[0u32, 7, 65535], f64::from), [0, 7, 65535]);
        assert_eq!(to_grey16(&[3.0f32, 12.0], f64::from), [3, 12]);
    }

    #[test]
    fn a_signed_range_is_stretched_over_16_bits() {
        // −1 000…3 000 HU: 4 000 steps, one for one, the order kept.
        let g = to_grey16(&[-1000i16, 0, 3000], f64::from);
        assert_eq!(g, [0, 16384, 65535]);
        let all: Vec<i16> = (-1000..=3000).collect();
        let g = to_grey16(&all, f64::from);
        assert!(g.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn ids_far_apart_are_spread_by_rank() {
        // A linear stretch would merge 1 and 2 (10^9 apart from 0 is the range).
        let g = to_grey16(&[0i64, 1, 2, 1_000_000_000], |x| x as f64);
        assert_eq!(g, [0, 21845, 43690, 65535]);
        let g = to_grey16(&[-0.0, 0.0, 1.0, 1e9, -1.0], |x| x);
        assert_eq!(g, [21845, 21845, 43690, 65535, 0]);
    }

    #[test]
    fn more_values_than_levels_are_stretched_and_non_finite_ones_saturate() {
        let mut v: Vec<f64> = (0..70_000).map(|i| f64::from(i) / 7.0).collect();
        v.extend([f64::NAN, f64::NEG_INFINITY, f64::INFINITY]);
        let g = to_grey16(&v, |x| x);
        assert_eq!(g[0], 0);
        assert_eq!(g[69_999], 65535);
        assert!(g[..70_000].windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(g[70_000..], [0, 0, 65535]);
    }

    #[test]
    fn one_value_or_none_finite_is_level_zero() {
        assert_eq!(to_grey16(&[2.5f64, 2.5], |x| x), [0, 0]);
        assert_eq!(to_grey16(&[f64::NAN, -0.5], |x| x), [0, 0]);
        assert_eq!(to_grey16(&[f64::NAN, f64::NAN], |x| x), [0, 0]);
    }
}

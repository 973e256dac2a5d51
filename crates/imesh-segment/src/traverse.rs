//! Supercover traversal: every pixel square a segment touches, in the order the segment reaches it.
//!
//! Triangle vertices are pixel centres or domain corners, so a median's ends (a vertex and the
//! midpoint of two vertices) lie on the quarter-pixel lattice. Working in integer quarter-pixel
//! coordinates makes every decision exact, including a median that runs through a pixel corner
//! (it touches all four squares there) or along a pixel edge (it touches the squares on both
//! sides).

/// A point in quarter-pixel units: `(4x, 4y)`.
pub type Quarter = [i64; 2];

/// Side of a pixel in quarter-pixel units.
const SIDE: i64 = 4;

/// Calls `visit(col, row)` for every pixel of the `width × height` grid whose closed square the
/// closed segment `a → b` touches, ordered by where the segment first touches it (pixels first
/// touched at the same point come in a fixed order). Pixels outside the grid are skipped.
///
/// ```
/// use imesh_segment::traverse::touched_pixels;
/// // From the centre of pixel (0, 0) to the centre of pixel (2, 0), along y = 0.5.
/// let mut seen = Vec::new();
/// touched_pixels([2, 2], [10, 2], 4, 4, |c, r| seen.push((c, r)));
/// assert_eq!(seen, vec![(0, 0), (1, 0), (2, 0)]);
/// // Through the corner shared by pixels (0, 0), (1, 0), (0, 1) and (1, 1).
/// seen.clear();
/// touched_pixels([2, 2], [6, 6], 4, 4, |c, r| seen.push((c, r)));
/// assert_eq!(seen, vec![(0, 0), (0, 1), (1, 0), (1, 1)]);
/// ```
pub fn touched_pixels(
    a: Quarter,
    b: Quarter,
    width: u32,
    height: u32,
    mut visit: impl FnMut(u32, u32),
) {
    if width == 0 || height == 0 {
        return;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (xmin, xmax) = (a[0].min(b[0]), a[0].max(b[0]));
    // Columns whose closed x-range meets [xmin, xmax].
    let c_lo = ceil_div(xmin - SIDE, SIDE).max(0);
    let c_hi = xmax.div_euclid(SIDE).min(i64::from(width) - 1);
    if c_lo > c_hi {
        return;
    }
    if dx == 0 {
        // Vertical: rows in travel order; on a pixel edge, both columns of each row.
        let (ymin, ymax) = (a[1].min(b[1]), a[1].max(b[1]));
        let r_lo = ceil_div(ymin - SIDE, SIDE).max(0);
        let r_hi = ymax.div_euclid(SIDE).min(i64::from(height) - 1);
        let mut row = |r: i64| {
            for c in c_lo..=c_hi {
                visit(c as u32, r as u32);
            }
        };
        if dy >= 0 {
            (r_lo..=r_hi).for_each(&mut row);
        } else {
            (r_lo..=r_hi).rev().for_each(&mut row);
        }
        return;
    }
    let span = Span::new(a, b, (c_lo, c_hi), height);
    if [a, b].iter().flatten().all(|v| v.abs() < STEPPED_LIMIT) {
        stepped_columns(&span, visit);
    } else {
        general_columns(&span, visit);
    }
}

/// A segment that is not vertical, over the grid columns `columns` (inclusive) of a grid
/// `height` rows high.
struct Span {
    a: Quarter,
    dx: i64,
    dy: i64,
    xmin: i64,
    xmax: i64,
    columns: (i64, i64),
    height: u32,
}

impl Span {
    fn new(a: Quarter, b: Quarter, columns: (i64, i64), height: u32) -> Self {
        Self {
            a,
            dx: b[0] - a[0],
            dy: b[1] - a[1],
            xmin: a[0].min(b[0]),
            xmax: a[0].max(b[0]),
            columns,
            height,
        }
    }
}

/// The columns of `span` in travel order, with the rows each touches, for any coordinates: the
/// segment's height at each column's x-limits as exact fractions (128-bit products), the rows by
/// division ([`stepped_columns`] is the same for coordinates under 2²⁹, without the divisions).
fn general_columns(span: &Span, mut visit: impl FnMut(u32, u32)) {
    let &Span {
        a,
        dx,
        dy,
        xmin,
        xmax,
        columns: (c_lo, c_hi),
        height,
    } = span;
    let columns: Box<dyn Iterator<Item = i64>> = if dx > 0 {
        Box::new(c_lo..=c_hi)
    } else {
        Box::new((c_lo..=c_hi).rev())
    };
    for c in columns {
        // The part of the segment over this column: y at its two x-limits, as fractions p / q.
        let (ylo, yhi) = {
            let x0 = (SIDE * c).max(xmin);
            let x1 = (SIDE * c + SIDE).min(xmax);
            let y_at = |x: i64| -> (i128, i128) {
                // y = a.y + (x − a.x)·dy/dx, with a positive denominator.
                let (num, den) = (
                    i128::from(a[1]) * i128::from(dx) + i128::from(x - a[0]) * i128::from(dy),
                    i128::from(dx),
                );
                if den < 0 {
                    (-num, -den)
                } else {
                    (num, den)
                }
            };
            let (p, q) = (y_at(x0), y_at(x1));
            // Order the two by value (cross-multiplied; both denominators are |dx|).
            if p.0 <= q.0 {
                (p, q)
            } else {
                (q, p)
            }
        };
        // Rows whose closed y-range meets [ylo, yhi].
        let r_lo = ceil_div_128(ylo.0 - i128::from(SIDE) * ylo.1, i128::from(SIDE) * ylo.1).max(0);
        let r_hi = floor_div_128(yhi.0, i128::from(SIDE) * yhi.1).min(i128::from(height) - 1);
        // Both bounds fit in 64 bits once clamped to the grid (an empty range stays empty).
        let (r_lo, r_hi) = (r_lo.min(i128::from(height)) as i64, r_hi.max(-1) as i64);
        visit_rows(c, (r_lo, r_hi), dy, &mut visit);
    }
}

/// Visits rows `r_lo..=r_hi` of column `c` in the direction the segment travels (`dy`).
fn visit_rows(c: i64, (r_lo, r_hi): (i64, i64), dy: i64, visit: &mut impl FnMut(u32, u32)) {
    if r_lo > r_hi {
        return;
    }
    let col = c as u32;
    if dy >= 0 {
        for r in r_lo..=r_hi {
            visit(col, r as u32);
        }
    } else {
        for r in (r_lo..=r_hi).rev() {
            visit(col, r as u32);
        }
    }
}

/// Coordinates (in quarter pixels) under which [`stepped_columns`] runs: every numerator it
/// forms, `a.y·|dx| + (x − a.x)·dy` with all of them under 2²⁹, stays under 2⁶¹.
const STEPPED_LIMIT: i64 = 1 << 29;

/// `n = q · d + r` with `0 ≤ r < d` (`d > 0`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Floor {
    q: i64,
    r: i64,
}

impl Floor {
    fn of(n: i64, d: i64) -> Self {
        Self {
            q: n.div_euclid(d),
            r: n.rem_euclid(d),
        }
    }

    /// `n + step` where `step` is `step.q · d + step.r`: no division.
    fn plus(self, step: Floor, d: i64) -> Self {
        let (q, r) = (self.q + step.q, self.r + step.r);
        if r >= d {
            Self { q: q + 1, r: r - d }
        } else {
            Self { q, r }
        }
    }

    /// `⌈n / d⌉`.
    fn ceil(self) -> i64 {
        self.q + i64::from(self.r > 0)
    }
}

/// The columns of `span` in travel order, with the rows each touches, as [`general_columns`]
/// finds them: the segment's height at a column's two x-limits is `y = N / |dx|`,
/// `N = a.y·|dx| + (x − a.x)·dy·sign(dx)`, and the rows are `⌈N_lo / 4|dx|⌉ − 1 ..= ⌊N_hi / 4|dx|⌋`.
/// On the lines between columns (x a multiple of 4) `N` grows by the same step from one to the
/// next, so its quotient and remainder by `4|dx|` are stepped, not divided (only the segment's
/// ends, inside a column, are divided).
fn stepped_columns(span: &Span, mut visit: impl FnMut(u32, u32)) {
    let &Span { a, dx, dy, .. } = span;
    let ((c_lo, c_hi), (xmin, xmax)) = (span.columns, (span.xmin, span.xmax));
    let slope = dx.signum() * dy;
    let den = SIDE * dx.abs();
    let numerator = |x: i64| a[1] * dx.abs() + (x - a[0]) * slope;
    let last_row = i64::from(span.height) - 1;
    // The lines between columns in travel order: entering column c, then leaving it.
    let forward = dx > 0;
    let (first_line, line_step) = if forward {
        (SIDE * c_lo, Floor::of(SIDE * slope, den))
    } else {
        (SIDE * (c_hi + 1), Floor::of(-SIDE * slope, den))
    };
    let mut line = Floor::of(numerator(first_line), den);
    for k in 0..=(c_hi - c_lo) {
        let c = if forward { c_lo + k } else { c_hi - k };
        let next = line.plus(line_step, den);
        // The segment's part over column c: its x-limits, clamped to the segment's ends.
        let (left, right) = if forward { (line, next) } else { (next, line) };
        let left = if SIDE * c < xmin {
            Floor::of(numerator(xmin), den)
        } else {
            left
        };
        let right = if SIDE * c + SIDE > xmax {
            Floor::of(numerator(xmax), den)
        } else {
            right
        };
        line = next;
        let (lo, hi) = (left.min(right), left.max(right));
        visit_rows(
            c,
            ((lo.ceil() - 1).max(0), hi.q.min(last_row)),
            dy,
            &mut visit,
        );
    }
}

fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

/// `⌊n / d⌋`, in 64 bits where both fit (always, for images of under 2²⁹ pixels a side):
/// a 128-bit division is a library call, several times slower.
fn floor_div_128(n: i128, d: i128) -> i128 {
    match (i64::try_from(n), i64::try_from(d)) {
        (Ok(n), Ok(d)) => i128::from(n.div_euclid(d)),
        _ => n.div_euclid(d),
    }
}

fn ceil_div_128(n: i128, d: i128) -> i128 {
    -floor_div_128(-n, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collect(a: Quarter, b: Quarter, w: u32, h: u32) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        touched_pixels(a, b, w, h, |c, r| v.push((c, r)));
        v
    }

    /// Brute force: a pixel is touched when the closed segment meets its closed square
    /// (checked by clipping the segment's parameter range to the square, exactly in rationals).
    fn touches(a: Quarter, b: Quarter, c: i64, r: i64) -> bool {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for (p, d, min, max) in [
            (a[0], b[0] - a[0], 4 * c, 4 * c + 4),
            (a[1], b[1] - a[1], 4 * r, 4 * r + 4),
        ] {
            if d == 0 {
                if p < min || p > max {
                    return false;
                }
            } else {
                let (t0, t1) = ((min - p) as f64 / d as f64, (max - p) as f64 / d as f64);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        lo <= hi
    }

    proptest::proptest! {
        /// The divisions take the 64-bit path where they can and give the 128-bit results,
        /// near zero, near the 64-bit limits and beyond them.
        #[test]
        fn divisions_match_128_bit_ones(
            n in proptest::prop_oneof![-1000i128..1000, proptest::num::i128::ANY],
            d in proptest::prop_oneof![1i128..100, 1i128..=i128::from(i64::MAX), 1i128..i128::MAX],
        ) {
            proptest::prop_assert_eq!(floor_div_128(n, d), n.div_euclid(d));
            if n > i128::MIN {
                proptest::prop_assert_eq!(ceil_div_128(n, d), -(-n).div_euclid(d));
            }
        }
    }

    proptest::proptest! {
        /// The stepped columns are the general ones, pixel for pixel and in the same order:
        /// short and long segments, either direction, partly or wholly off the grid, with ends
        /// on and off the lines between pixels, up to the stepped path's limit.
        #[test]
        fn stepped_columns_are_the_general_ones(
            a in proptest::array::uniform2(-40i64..200),
            b in proptest::array::uniform2(-40i64..200),
            far in proptest::array::uniform2(-(STEPPED_LIMIT - 1)..STEPPED_LIMIT),
            use_far in proptest::bool::ANY,
            (w, h) in (1u32..50, 1u32..50),
        ) {
            let b = if use_far { far } else { b };
            proptest::prop_assume!(a[0] != b[0]);
            let (xmin, xmax) = (a[0].min(b[0]), a[0].max(b[0]));
            let c_lo = ceil_div(xmin - SIDE, SIDE).max(0);
            let c_hi = xmax.div_euclid(SIDE).min(i64::from(w) - 1);
            proptest::prop_assume!(c_lo <= c_hi);
            let span = Span::new(a, b, (c_lo, c_hi), h);
            let (mut stepped, mut general) = (Vec::new(), Vec::new());
            stepped_columns(&span, |c, r| stepped.push((c, r)));
            general_columns(&span, |c, r| general.push((c, r)));
            proptest::prop_assert_eq!(stepped, general);
        }
    }

    #[test]
    fn matches_brute_force_on_lattice_segments() {
        let mut s = 12345u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 41) as i64
        };
        for _ in 0..3000 {
            let (a, b) = ([next(), next()], [next(), next()]);
            let got = collect(a, b, 10, 10);
            let mut sorted = got.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(
                sorted.len(),
                got.len(),
                "a pixel visited twice: {a:?} {b:?}"
            );
            let want: Vec<(u32, u32)> = (0..10)
                .flat_map(|c| (0..10).map(move |r| (c, r)))
                .filter(|&(c, r)| touches(a, b, i64::from(c), i64::from(r)))
                .collect();
            assert_eq!(sorted, want, "{a:?} → {b:?}");
        }
    }

    #[test]
    fn a_segment_along_a_pixel_edge_touches_both_sides() {
        // x = 1 (quarter 4), from y = 0.5 to 2.5.
        let got = collect([4, 2], [4, 10], 4, 4);
        assert_eq!(got, vec![(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)]);
    }

    #[test]
    fn order_follows_the_direction() {
        let got = collect([14, 2], [2, 2], 4, 1);
        assert_eq!(got, vec![(3, 0), (2, 0), (1, 0), (0, 0)]);
    }
}

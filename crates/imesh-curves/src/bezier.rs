//! Cubic Bézier curves: de Casteljau evaluation and splitting, closest points, and the
//! least-squares fit of a chain with fixed ends (the paper's section V-C).

use imesh_geom::Point;
use nalgebra::DMatrix;

use crate::distance::{segment_distance, segment_parameter};

/// A cubic Bézier curve `b(t) = Σ Bᵢ³(t) pᵢ`, `t ∈ [0, 1]`.
///
/// ```
/// use imesh_curves::CubicBezier;
/// use imesh_geom::Point;
/// let c = CubicBezier::new([
///     Point::new(0.0, 0.0), Point::new(1.0, 2.0), Point::new(3.0, 2.0), Point::new(4.0, 0.0),
/// ]);
/// let (left, right) = c.split(0.25);
/// assert_eq!(left.control[3], c.eval(0.25));
/// assert!((right.eval(0.5).x - c.eval(0.625).x).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicBezier {
    /// The four control points; the curve runs from `control[0]` to `control[3]`.
    pub control: [Point; 4],
}

impl CubicBezier {
    /// The curve with these control points.
    pub const fn new(control: [Point; 4]) -> Self {
        Self { control }
    }

    /// The straight segment from `a` to `b`, uniformly parametrised (inner control points at
    /// one and two thirds).
    pub fn segment(a: Point, b: Point) -> Self {
        Self::new([a, a + (b - a) * (1.0 / 3.0), a + (b - a) * (2.0 / 3.0), b])
    }

    /// The same curve run the other way: `reversed().eval(t) == eval(1 − t)`.
    ///
    /// ```
    /// use imesh_curves::CubicBezier;
    /// use imesh_geom::Point;
    /// let c = CubicBezier::new([Point::new(0.0, 0.0), Point::new(1.0, 2.0), Point::new(3.0, 2.0), Point::new(4.0, 0.0)]);
    /// assert_eq!(c.reversed().control[0], Point::new(4.0, 0.0));
    /// assert!(c.reversed().eval(0.25).distance_squared(c.eval(0.75)) < 1e-24);
    /// ```
    pub fn reversed(&self) -> Self {
        let c = self.control;
        Self::new([c[3], c[2], c[1], c[0]])
    }

    /// The point at parameter `t`, by de Casteljau's algorithm (stable for any `t`).
    pub fn eval(&self, t: f64) -> Point {
        self.casteljau(t).0
    }

    /// The first derivative `b'(t)`.
    pub fn derivative(&self, t: f64) -> Point {
        let [p0, p1, p2, p3] = self.control;
        let s = 1.0 - t;
        ((p1 - p0) * (s * s) + (p2 - p1) * (2.0 * s * t) + (p3 - p2) * (t * t)) * 3.0
    }

    /// The second derivative `b''(t)`.
    pub fn second_derivative(&self, t: f64) -> Point {
        let [p0, p1, p2, p3] = self.control;
        let a = p2 - p1 * 2.0 + p0;
        let b = p3 - p2 * 2.0 + p1;
        (a * (1.0 - t) + b * t) * 6.0
    }

    /// The two halves of the curve at `t`: `left` covers `[0, t]` and `right` `[t, 1]`, each
    /// reparametrised to `[0, 1]`; both are exactly the original curve's pieces (de Casteljau).
    pub fn split(&self, t: f64) -> (CubicBezier, CubicBezier) {
        let (_, left, right) = self.casteljau(t);
        (CubicBezier::new(left), CubicBezier::new(right))
    }

    /// The piece of the curve over `[t0, t1]` (`t0 < t1`), reparametrised to `[0, 1]`.
    pub fn sub_curve(&self, t0: f64, t1: f64) -> CubicBezier {
        if t0 <= 0.0 && t1 >= 1.0 {
            return *self;
        }
        let (_, right) = self.split(t0);
        if t0 >= 1.0 {
            return right;
        }
        let (piece, _) = right.split(((t1 - t0) / (1.0 - t0)).clamp(0.0, 1.0));
        let mut piece = piece;
        // The ends are the curve's own points at t0 and t1, exactly as `eval` gives them.
        piece.control[0] = self.eval(t0);
        piece.control[3] = self.eval(t1);
        piece
    }

    /// The de Casteljau triangle at `t`: the point, and the control polygons of both halves.
    fn casteljau(&self, t: f64) -> (Point, [Point; 4], [Point; 4]) {
        let lerp = |a: Point, b: Point| a + (b - a) * t;
        let [p0, p1, p2, p3] = self.control;
        let (a, b, c) = (lerp(p0, p1), lerp(p1, p2), lerp(p2, p3));
        let (d, e) = (lerp(a, b), lerp(b, c));
        let f = lerp(d, e);
        (f, [p0, a, d, f], [f, e, c, p3])
    }

    /// The parameter of the point of the curve closest to `q`, starting from the parameter
    /// `guess`: a few Newton steps on `(b(t) − q) · b'(t) = 0`, kept only when they bring the
    /// point closer, compared with the ends and a coarse sampling.
    pub fn closest_parameter(&self, q: Point, guess: f64) -> f64 {
        let distance = |t: f64| self.eval(t).distance_squared(q);
        let mut best = guess.clamp(0.0, 1.0);
        let mut nearest = distance(best);
        for k in 0..=16 {
            let t = f64::from(k) / 16.0;
            let d = distance(t);
            if d < nearest {
                (best, nearest) = (t, d);
            }
        }
        self.newton_projection(q, best)
    }

    /// Newton steps on `(b(t) − q) · b'(t) = 0` from `t`, each kept only when it brings the point
    /// closer: the projection when `t` is already near it.
    fn newton_projection(&self, q: Point, t: f64) -> f64 {
        let mut t = t.clamp(0.0, 1.0);
        let mut r = self.eval(t) - q;
        let mut current = r.x * r.x + r.y * r.y;
        for _ in 0..8 {
            let d1 = self.derivative(t);
            let d2 = self.second_derivative(t);
            let f = r.x * d1.x + r.y * d1.y;
            let fp = d1.x * d1.x + d1.y * d1.y + r.x * d2.x + r.y * d2.y;
            if fp <= 0.0 || !fp.is_finite() {
                break;
            }
            let next = (t - f / fp).clamp(0.0, 1.0);
            let r_next = self.eval(next) - q;
            let moved = r_next.x * r_next.x + r_next.y * r_next.y;
            if moved > current {
                break;
            }
            let step = (next - t).abs();
            (t, r, current) = (next, r_next, moved);
            // Parameter steps below 1e-12 move the point by less than 1e-12 of the curve's
            // speed: the projection has converged for any use here.
            if step < 1e-12 {
                break;
            }
        }
        t
    }

    /// The distance from `q` to the curve (through [`CubicBezier::closest_parameter`]).
    pub fn distance(&self, q: Point, guess: f64) -> f64 {
        self.eval(self.closest_parameter(q, guess))
            .distance_squared(q)
            .sqrt()
    }
}

/// Options of [`fit_cubic`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Most Levenberg–Marquardt steps after the chord-length fit: each projects the chain's
    /// points on the current curve (Newton) and moves the inner control points to lower the sum
    /// of squared point-to-curve distances; a step is kept only when that sum falls. 0 keeps the
    /// paper's plain chord-length fit.
    pub reparametrise: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { reparametrise: 6 }
    }
}

/// A fitted curve and how far the chain's points are from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveFit {
    /// The curve; its ends are the chain's ends.
    pub curve: CubicBezier,
    /// The largest distance from a chain point to the curve.
    pub max_error: f64,
    /// The root mean square of those distances.
    pub rms_error: f64,
    /// The largest distance from a point of the curve to the chain (the other half of the
    /// Hausdorff distance: a cubic can swing away between the points it fits).
    pub curve_deviation: f64,
}

impl CurveFit {
    /// The Hausdorff distance between the curve and the chain (as sampled).
    pub fn hausdorff(&self) -> f64 {
        self.max_error.max(self.curve_deviation)
    }
}

/// Fits a cubic Bézier to the chain `points` (at least two): ends fixed at the chain's ends, the
/// two inner control points by linear least squares over a chord-length parametrisation (QR
/// through `nalgebra`, the paper's systems `K x = d`, `K y = f`), then improved by
/// reparametrisation: the points are projected on the curve and the control points moved to
/// minimise the distances along the curve's normals (Levenberg–Marquardt, which converges where
/// alternating projection and refitting crawls). Chains of fewer than four points get the
/// straight segment, and so does any chain that the segment fits better (a cubic through a
/// zigzag can overshoot).
///
/// ```
/// use imesh_curves::{fit_cubic, CubicBezier, FitOptions};
/// use imesh_geom::Point;
/// let arc: Vec<Point> = (0..=12)
///     .map(|i| { let a = std::f64::consts::FRAC_PI_2 * f64::from(i) / 12.0; Point::new(10.0 * a.cos(), 10.0 * a.sin()) })
///     .collect();
/// let fit = fit_cubic(&arc, &FitOptions::default());
/// assert!(fit.max_error < 0.01);
/// assert_eq!(fit.curve.control[0], arc[0]);
/// ```
pub fn fit_cubic(points: &[Point], options: &FitOptions) -> CurveFit {
    let n = points.len();
    let (first, last) = (points[0], points[n - 1]);
    let mut t = chord_length(points);
    let chord_fit = measure_segment(first, last, points);
    if n < 4 {
        return chord_fit;
    }
    let Some(curve) = least_squares(points, &t) else {
        return chord_fit;
    };
    let mut best = measure(curve, points, &mut t, false);
    let mut damping = 1e-3;
    for _ in 0..options.reparametrise {
        if best.rms_error <= 1e-14 * scale(points) {
            break;
        }
        let Some(step) = normal_step(best.curve, points, &t) else {
            break;
        };
        // Levenberg–Marquardt: shrink the step (more damping) until the error falls.
        let mut improved = false;
        for _ in 0..12 {
            let Some(delta) = step.solve(damping) else {
                break;
            };
            let [p0, p1, p2, p3] = best.curve.control;
            let candidate = CubicBezier::new([
                p0,
                p1 + Point::new(delta[0], delta[1]),
                p2 + Point::new(delta[2], delta[3]),
                p3,
            ]);
            let mut projected = t.clone();
            let fit = measure(candidate, points, &mut projected, true);
            if fit.rms_error < best.rms_error {
                best = fit;
                t = projected;
                damping = (damping / 4.0).max(1e-12);
                improved = true;
                break;
            }
            damping *= 8.0;
        }
        if !improved {
            break;
        }
    }
    best.curve_deviation = curve_deviation(&best.curve, points, &t);
    if chord_fit.hausdorff() <= best.hausdorff() {
        chord_fit
    } else {
        best
    }
}

/// Fits a cubic Bézier to the chain `points` (at least two) whose ends leave the chain's ends
/// along the given directions: `start` from the first point, `end` from the last (into the
/// curve; any length, not zero). The arms' lengths (`|P₁ − P₀|`, `|P₂ − P₃|`) are `arms` where
/// given, else fitted (least squares, then a few reprojections, as Schneider's fit does); an
/// arm a chain of fewer than four points does not determine is a third of the chord. `None`
/// when a fitted arm is not positive (the curve would leave the other way).
///
/// ```
/// use imesh_curves::fit_cubic_with_tangents;
/// use imesh_geom::Point;
/// // A quarter circle, its end tangents given: the classic four-point approximation.
/// let arc: Vec<Point> = (0..=24)
///     .map(|i| { let a = std::f64::consts::FRAC_PI_2 * f64::from(i) / 24.0; Point::new(a.cos(), a.sin()) })
///     .collect();
/// let fit = fit_cubic_with_tangents(&arc, Point::new(0.0, 1.0), Point::new(1.0, 0.0), [None, None]).unwrap();
/// assert!(fit.max_error < 1e-3);
/// assert!((fit.curve.control[1].y - 0.5523).abs() < 1e-3); // the known 0.5523 of the radius
/// // The first arm held at 0.3: the second makes up for it.
/// let held = fit_cubic_with_tangents(&arc, Point::new(0.0, 1.0), Point::new(1.0, 0.0), [Some(0.3), None]).unwrap();
/// assert_eq!(held.curve.control[1], Point::new(1.0, 0.3));
/// assert!(held.max_error < 0.05);
/// ```
pub fn fit_cubic_with_tangents(
    points: &[Point],
    start: Point,
    end: Point,
    arms: [Option<f64>; 2],
) -> Option<CurveFit> {
    let n = points.len();
    let (p0, p3) = (points.first().copied()?, points.last().copied()?);
    let unit = |d: Point| {
        let len = (d.x * d.x + d.y * d.y).sqrt();
        (len > 0.0 && len.is_finite()).then(|| d * (1.0 / len))
    };
    let (u, w) = (unit(start)?, unit(end)?);
    let third = p0.distance_squared(p3).sqrt() / 3.0;
    let curve_of = |a: f64, b: f64| CubicBezier::new([p0, p0 + u * a, p3 + w * b, p3]);
    let mut t = chord_length(points);
    let mut lengths = (arms[0].unwrap_or(third), arms[1].unwrap_or(third));
    for refit in 0..=TANGENT_REFITS {
        if n < 4 || (arms[0].is_some() && arms[1].is_some()) {
            break;
        }
        // Σ |α B₁ u + β B₂ w − rᵢ|² over the inner points, rᵢ the point less the ends' part;
        // a given arm moves to the right-hand side.
        let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (&p, &ti) in points[1..n - 1].iter().zip(&t[1..n - 1]) {
            let s = 1.0 - ti;
            let (c0, c1, c2, c3) = (s * s * s, 3.0 * s * s * ti, 3.0 * s * ti * ti, ti * ti * ti);
            let mut r = p - p0 * (c0 + c1) - p3 * (c2 + c3);
            let (x, y) = (u * c1, w * c2);
            if let Some(a) = arms[0] {
                r = r - x * a;
            }
            if let Some(b) = arms[1] {
                r = r - y * b;
            }
            a11 += x.x * x.x + x.y * x.y;
            a12 += x.x * y.x + x.y * y.y;
            a22 += y.x * y.x + y.y * y.y;
            b1 += x.x * r.x + x.y * r.y;
            b2 += y.x * r.x + y.y * r.y;
        }
        let solved = match arms {
            [Some(a), None] => (a22 > 0.0).then(|| (a, b2 / a22)),
            [None, Some(b)] => (a11 > 0.0).then(|| (b1 / a11, b)),
            _ => {
                let det = a11 * a22 - a12 * a12;
                (det.abs() > 1e-12 * (a11 * a22).max(f64::MIN_POSITIVE))
                    .then(|| ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det))
            }
        };
        let Some(solved) = solved else { break };
        lengths = solved;
        // The points' projections on the new curve are its next parameters (a first curve may
        // be far from the chord-length guesses: a global search).
        measure(curve_of(lengths.0, lengths.1), points, &mut t, refit > 0);
    }
    let (a, b) = lengths;
    if !(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite()) {
        return None;
    }
    let mut fit = measure(curve_of(a, b), points, &mut t, false);
    fit.curve_deviation = curve_deviation(&fit.curve, points, &t);
    Some(fit)
}

/// Reprojections of [`fit_cubic_with_tangents`] after its first fit.
const TANGENT_REFITS: usize = 4;

/// The least-squares cubic through `points` at the given parameters `t` (one per point,
/// `t[0] = 0`, last 1, increasing): ends fixed, inner control points by QR. Points sampled from a
/// cubic at their parameters give that cubic back. `None` when fewer than four points or the
/// parameters do not determine the inner control points (the system is rank-deficient).
///
/// ```
/// use imesh_curves::{fit_cubic_at, CubicBezier};
/// use imesh_geom::Point;
/// let c = CubicBezier::new([Point::new(0.0, 0.0), Point::new(1.0, 3.0), Point::new(4.0, -1.0), Point::new(5.0, 1.0)]);
/// let t: Vec<f64> = (0..8).map(|i| f64::from(i) / 7.0).collect();
/// let samples: Vec<Point> = t.iter().map(|&t| c.eval(t)).collect();
/// let fit = fit_cubic_at(&samples, &t).unwrap();
/// assert!((fit.control[1].x - 1.0).abs() < 1e-12 && (fit.control[2].y + 1.0).abs() < 1e-12);
/// ```
pub fn fit_cubic_at(points: &[Point], t: &[f64]) -> Option<CubicBezier> {
    if points.len() < 4 || t.len() != points.len() {
        return None;
    }
    least_squares(points, t)
}

/// The largest coordinate magnitude of `points` (at least 1).
fn scale(points: &[Point]) -> f64 {
    points
        .iter()
        .map(|p| p.x.abs().max(p.y.abs()))
        .fold(1.0, f64::max)
}

/// The Gauss–Newton normal equations for the inner control points, with each point's residual
/// measured along the curve's normal at its projection (moving along the tangent only slides the
/// foot point, which the next projection absorbs).
struct NormalStep {
    matrix: nalgebra::Matrix4<f64>,
    rhs: nalgebra::Vector4<f64>,
}

impl NormalStep {
    /// `(JᵀJ + μ·diag(JᵀJ)) δ = Jᵀr`: the damped step, μ = `damping`.
    fn solve(&self, damping: f64) -> Option<nalgebra::Vector4<f64>> {
        let mut m = self.matrix;
        let floor = 1e-12 * m.trace().max(f64::MIN_POSITIVE);
        for k in 0..4 {
            m[(k, k)] += damping * m[(k, k)].max(floor);
        }
        m.cholesky().map(|c| c.solve(&self.rhs))
    }
}

fn normal_step(curve: CubicBezier, points: &[Point], t: &[f64]) -> Option<NormalStep> {
    let mut matrix = nalgebra::Matrix4::zeros();
    let mut rhs = nalgebra::Vector4::zeros();
    let n = points.len();
    for (&p, &ti) in points[1..n - 1].iter().zip(&t[1..n - 1]) {
        let d = curve.derivative(ti);
        let len = (d.x * d.x + d.y * d.y).sqrt();
        if len == 0.0 || !len.is_finite() {
            continue;
        }
        let normal = Point::new(-d.y / len, d.x / len);
        let r = curve.eval(ti) - p;
        let s = 1.0 - ti;
        let (b1, b2) = (3.0 * s * s * ti, 3.0 * s * ti * ti);
        let row =
            nalgebra::Vector4::new(b1 * normal.x, b1 * normal.y, b2 * normal.x, b2 * normal.y);
        matrix += row * row.transpose();
        rhs -= row * (normal.x * r.x + normal.y * r.y);
    }
    (matrix.trace() > 0.0).then_some(NormalStep { matrix, rhs })
}

/// Chord-length parameters of `points` in `[0, 1]` (uniform when the chain has no length).
fn chord_length(points: &[Point]) -> Vec<f64> {
    let mut t = Vec::with_capacity(points.len());
    let mut total = 0.0;
    t.push(0.0);
    for w in points.windows(2) {
        total += w[0].distance_squared(w[1]).sqrt();
        t.push(total);
    }
    let n = points.len();
    if total > 0.0 {
        t.iter_mut().for_each(|x| *x /= total);
    } else {
        t.iter_mut()
            .enumerate()
            .for_each(|(i, x)| *x = i as f64 / (n - 1) as f64);
    }
    t[n - 1] = 1.0;
    t
}

/// The inner control points minimising `Σ |b(tᵢ) − pᵢ|²` with the ends fixed: the paper's two
/// systems `K x = d`, `K y = f`, solved together (two right-hand sides) by QR.
fn least_squares(points: &[Point], t: &[f64]) -> Option<CubicBezier> {
    let n = points.len();
    let (p0, p3) = (points[0], points[n - 1]);
    let mut k = DMatrix::<f64>::zeros(n, 2);
    let mut rhs = DMatrix::<f64>::zeros(n, 2);
    for (i, (&p, &ti)) in points.iter().zip(t).enumerate() {
        let s = 1.0 - ti;
        let (b0, b1, b2, b3) = (s * s * s, 3.0 * s * s * ti, 3.0 * s * ti * ti, ti * ti * ti);
        k[(i, 0)] = b1;
        k[(i, 1)] = b2;
        rhs[(i, 0)] = p.x - (b0 * p0.x + b3 * p3.x);
        rhs[(i, 1)] = p.y - (b0 * p0.y + b3 * p3.y);
    }
    // Normal equations through QR of K (2 columns): R x = Qᵀ rhs.
    let qr = k.qr();
    let r = qr.r();
    if r[(0, 0)].abs() < 1e-12 || r[(1, 1)].abs() < 1e-12 {
        return None;
    }
    let qt_rhs = qr.q().transpose() * rhs;
    let solution = r.solve_upper_triangular(&qt_rhs)?;
    let p1 = Point::new(solution[(0, 0)], solution[(0, 1)]);
    let p2 = Point::new(solution[(1, 0)], solution[(1, 1)]);
    (p1.is_finite() && p2.is_finite()).then_some(CubicBezier::new([p0, p1, p2, p3]))
}

/// The fit errors of the straight segment `ab` (projections in closed form).
fn measure_segment(a: Point, b: Point, points: &[Point]) -> CurveFit {
    let ab = b - a;
    let len2 = ab.x * ab.x + ab.y * ab.y;
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    for &p in points {
        let t = if len2 > 0.0 {
            (((p.x - a.x) * ab.x + (p.y - a.y) * ab.y) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d2 = p.distance_squared(a + ab * t);
        max = max.max(d2.sqrt());
        sum += d2;
    }
    let curve = CubicBezier::segment(a, b);
    let t: Vec<f64> = points.iter().map(|&p| segment_parameter(a, b, p)).collect();
    CurveFit {
        curve,
        max_error: max,
        rms_error: (sum / points.len() as f64).sqrt(),
        curve_deviation: curve_deviation(&curve, points, &t),
    }
}

/// How far the curve strays from the chain `points` (whose projections on the curve are at `t`):
/// the curve is sampled between consecutive projections (distance to the nearby chain edges) and
/// uniformly (distance to the whole chain), and the largest distance is returned. An upper
/// bound of the true value at the samples.
fn curve_deviation(curve: &CubicBezier, points: &[Point], t: &[f64]) -> f64 {
    let n = points.len();
    if n < 2 {
        return 0.0;
    }
    let near = |q: Point, range: std::ops::Range<usize>| {
        range
            .map(|j| segment_distance(points[j], points[j + 1], q))
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst: f64 = 0.0;
    for i in 0..n - 1 {
        let window = i.saturating_sub(2)..(i + 3).min(n - 1);
        for s in [0.25, 0.5, 0.75] {
            let q = curve.eval(t[i] + (t[i + 1] - t[i]) * s);
            worst = worst.max(near(q, window.clone()));
        }
    }
    for k in 0..=32 {
        let q = curve.eval(f64::from(k) / 32.0);
        worst = worst.max(near(q, 0..n - 1));
    }
    worst
}

/// The fit errors of `curve` to `points`; `t` holds each point's parameter guess on entry and
/// its projection on the curve on return (`near`: the guesses are projections on a nearby curve,
/// so Newton alone finds the new ones).
fn measure(curve: CubicBezier, points: &[Point], t: &mut [f64], near: bool) -> CurveFit {
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    for (&p, ti) in points.iter().zip(t.iter_mut()) {
        *ti = if near {
            curve.newton_projection(p, *ti)
        } else {
            curve.closest_parameter(p, *ti)
        };
        let d = curve.eval(*ti).distance_squared(p).sqrt();
        max = max.max(d);
        sum += d * d;
    }
    CurveFit {
        curve,
        max_error: max,
        rms_error: (sum / points.len() as f64).sqrt(),
        curve_deviation: 0.0,
    }
}

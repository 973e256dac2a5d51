//! Powell's conjugate direction method as an `argmin` [`Solver`]: derivative-free minimisation
//! over `Vec<f64>` by Brent line searches along a set of directions, the direction of largest
//! decrease being replaced by the iteration's net displacement when that keeps the set
//! conjugate (Powell 1964; the replacement test of Brent 1973, as in Numerical Recipes).
//!
//! Costs may be `+∞` (an infeasible point): line searches treat such points as worse than any
//! finite one, so the iterates stay feasible when the start is.

use std::convert::Infallible;

use argmin::core::{
    CostFunction, Error, IterState, Problem, Solver, State, TerminationReason, TerminationStatus,
    KV,
};

/// One search direction: a coordinate axis (stored as its index, so that the initial set costs
/// nothing for many variables) or a dense vector.
#[derive(Clone, Debug, PartialEq)]
enum Direction {
    Axis(usize),
    Dense(Vec<f64>),
}

impl Direction {
    /// `x + α d`, written into `y` (a line search evaluates many steps: one buffer serves all).
    fn step_into(&self, x: &[f64], alpha: f64, y: &mut Vec<f64>) {
        y.clear();
        y.extend_from_slice(x);
        self.step_in_place(y, alpha);
    }

    /// `x ← x + α d`.
    fn step_in_place(&self, x: &mut [f64], alpha: f64) {
        match self {
            Direction::Axis(i) => x[*i] += alpha,
            Direction::Dense(d) => x.iter_mut().zip(d).for_each(|(x, d)| *x += alpha * d),
        }
    }
}

/// Work vectors of one iteration, kept between iterations and between minimisations (the
/// local optimiser runs hundreds of thousands of two-variable ones).
#[derive(Clone, Debug, Default)]
struct Buffers {
    /// The iteration's start.
    start: Vec<f64>,
    /// The point a line search evaluates, and the extrapolated point.
    trial: Vec<f64>,
}

/// Powell's method.
///
/// The state's cost is the value at the state's parameter; every iteration runs one line search
/// per direction, then possibly one along the net displacement. It stops when an iteration
/// lowers the cost by less than `tolerance` relatively, or at the executor's iteration cap.
/// [`Powell::minimise`] runs the same iterations on a plain cost closure, without an executor.
///
/// ```
/// use argmin::core::{CostFunction, Error, Executor};
/// use imesh_optim::Powell;
/// struct Rosenbrock;
/// impl CostFunction for Rosenbrock {
///     type Param = Vec<f64>;
///     type Output = f64;
///     fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
///         Ok((1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2))
///     }
/// }
/// let result = Executor::new(Rosenbrock, Powell::new(0.1))
///     .configure(|s| s.param(vec![-1.2, 1.0]).max_iters(200))
///     .run()?;
/// let best = result.state().best_param.as_ref().unwrap();
/// assert!((best[0] - 1.0).abs() < 1e-4 && (best[1] - 1.0).abs() < 1e-4);
/// # Ok::<(), Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Powell {
    directions: Vec<Direction>,
    buffers: Buffers,
    initial_step: f64,
    tolerance: f64,
    line_tolerance: f64,
    line_evaluations: usize,
}

/// The golden ratio, the expansion factor of bracketing.
const GOLD: f64 = 1.618_033_988_749_895;
/// `(3 − √5) / 2`, the golden-section fraction of Brent's method.
const CGOLD: f64 = 0.381_966_011_250_105;

impl Powell {
    /// Powell's method whose first line searches try steps of `initial_step` (the scale of the
    /// variables), with relative tolerance `1e-8` and line searches of at most 40 evaluations.
    pub fn new(initial_step: f64) -> Self {
        Self {
            directions: Vec::new(),
            buffers: Buffers::default(),
            initial_step: 1.0,
            tolerance: 1e-8,
            line_tolerance: 1e-6,
            line_evaluations: 40,
        }
        .with_initial_step(initial_step)
    }

    /// Stops when an iteration lowers the cost by less than this fraction of it.
    #[must_use]
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance.max(0.0);
        self
    }

    /// Line searches stop when the step is known within this fraction of `initial_step`, or after
    /// `evaluations` cost evaluations.
    #[must_use]
    pub fn with_line_search(mut self, tolerance: f64, evaluations: usize) -> Self {
        self.line_tolerance = tolerance.max(f64::EPSILON);
        self.line_evaluations = evaluations.max(4);
        self
    }

    /// Minimises along `d` from `x` (cost `fx`): returns the best step and its cost (`(0, fx)`
    /// when no step along `±d` lowers the cost).
    fn line_minimum<E>(
        &self,
        cost: &mut impl FnMut(&Vec<f64>) -> Result<f64, E>,
        x: &[f64],
        d: &Direction,
        fx: f64,
        y: &mut Vec<f64>,
    ) -> Result<(f64, f64), E> {
        let mut budget = self.line_evaluations;
        let mut f = |alpha: f64, budget: &mut usize| -> Result<f64, E> {
            *budget = budget.saturating_sub(1);
            d.step_into(x, alpha, y);
            let c = cost(y)?;
            Ok(if c.is_nan() { f64::INFINITY } else { c })
        };
        // Bracket: find a downhill step (shrinking it past infeasible or uphill points), then
        // expand by the golden ratio until the cost rises again.
        let (a, fa) = (0.0, fx);
        let mut step = self.initial_step;
        let mut found = None;
        for _ in 0..6 {
            for s in [step, -step] {
                let fs = f(s, &mut budget)?;
                if fs < fa {
                    found = Some((s, fs));
                    break;
                }
            }
            if found.is_some() {
                break;
            }
            step *= 0.2;
        }
        let Some((mut b, mut fb)) = found else {
            return Ok((0.0, fx));
        };
        let mut lo = a;
        let hi = loop {
            let c = b + GOLD * (b - lo);
            let fc = f(c, &mut budget)?;
            if fc < fb && budget <= self.line_evaluations / 2 {
                // Still falling but out of budget: take the furthest point.
                return Ok((c, fc));
            }
            if fc >= fb {
                break c;
            }
            lo = b;
            (b, fb) = (c, fc);
        };
        // Brent's method on [lo, hi] around b: parabolic steps through the three best points
        // when they are finite and fall inside, golden sections otherwise.
        let (mut lo, mut hi) = if lo < hi { (lo, hi) } else { (hi, lo) };
        let (mut xb, mut fxb) = (b, fb);
        let (mut w, mut fw, mut v, mut fv) = (b, fb, b, fb);
        let (mut e, mut dstep) = (0.0f64, 0.0f64);
        let tol_abs = self.line_tolerance * self.initial_step;
        while budget > 0 {
            let mid = 0.5 * (lo + hi);
            let tol1 = tol_abs + 1e-10 * xb.abs();
            let tol2 = 2.0 * tol1;
            if (xb - mid).abs() <= tol2 - 0.5 * (hi - lo) {
                break;
            }
            let mut golden = true;
            if e.abs() > tol1 && fw.is_finite() && fv.is_finite() {
                let r = (xb - w) * (fxb - fv);
                let mut q = (xb - v) * (fxb - fw);
                let mut p = (xb - v) * q - (xb - w) * r;
                q = 2.0 * (q - r);
                if q > 0.0 {
                    p = -p;
                }
                q = q.abs();
                let e_old = e;
                if p.abs() < (0.5 * q * e_old).abs() && p > q * (lo - xb) && p < q * (hi - xb) {
                    e = dstep;
                    dstep = p / q;
                    let u = xb + dstep;
                    if u - lo < tol2 || hi - u < tol2 {
                        dstep = if mid >= xb { tol1 } else { -tol1 };
                    }
                    golden = false;
                }
            }
            if golden {
                e = if xb >= mid { lo - xb } else { hi - xb };
                dstep = CGOLD * e;
            }
            let u = if dstep.abs() >= tol1 {
                xb + dstep
            } else {
                xb + tol1.copysign(dstep)
            };
            let fu = f(u, &mut budget)?;
            if fu <= fxb {
                if u >= xb {
                    lo = xb;
                } else {
                    hi = xb;
                }
                (v, fv, w, fw, xb, fxb) = (w, fw, xb, fxb, u, fu);
            } else {
                if u < xb {
                    lo = u;
                } else {
                    hi = u;
                }
                if fu <= fw || w == xb {
                    (v, fv, w, fw) = (w, fw, u, fu);
                } else if fu <= fv || v == xb || v == w {
                    (v, fv) = (u, fu);
                }
            }
        }
        Ok((xb, fxb))
    }

    /// One iteration from `x` (cost `f0`), moving `x`: a line search along each direction,
    /// then possibly one along the net displacement, which may replace the direction of largest
    /// decrease. Returns the cost reached.
    fn iterate<E>(
        &mut self,
        cost: &mut impl FnMut(&Vec<f64>) -> Result<f64, E>,
        x: &mut [f64],
        f0: f64,
    ) -> Result<f64, E> {
        let mut buffers = std::mem::take(&mut self.buffers);
        let result = self.iterate_with(cost, x, f0, &mut buffers);
        self.buffers = buffers;
        result
    }

    /// [`Powell::iterate`] with the work vectors taken out of `self`.
    fn iterate_with<E>(
        &mut self,
        cost: &mut impl FnMut(&Vec<f64>) -> Result<f64, E>,
        x: &mut [f64],
        f0: f64,
        buffers: &mut Buffers,
    ) -> Result<f64, E> {
        let Buffers { start, trial } = buffers;
        start.clear();
        start.extend_from_slice(x);
        let mut fx = f0;
        let (mut biggest, mut biggest_at) = (0.0, 0);
        for (i, d) in self.directions.iter().enumerate() {
            let (alpha, f) = self.line_minimum(cost, x, d, fx, trial)?;
            if f < fx {
                d.step_in_place(x, alpha);
                if fx - f > biggest {
                    (biggest, biggest_at) = (fx - f, i);
                }
                fx = f;
            }
        }
        // Extrapolate along the net displacement; adopt it as a direction only when Powell's test
        // says the set stays conjugate (the largest single decrease did not dominate).
        if fx < f0 {
            trial.clear();
            trial.extend(x.iter().zip(start.iter()).map(|(a, b)| a + (a - b)));
            let fe = cost(trial)?;
            if fe < f0 {
                let t = 2.0 * (f0 - 2.0 * fx + fe) * (f0 - fx - biggest).powi(2)
                    - biggest * (f0 - fe).powi(2);
                if t < 0.0 {
                    let displacement = x.iter().zip(start.iter()).map(|(a, b)| a - b);
                    let d = Direction::Dense(displacement.collect());
                    let (alpha, f) = self.line_minimum(cost, x, &d, fx, trial)?;
                    if f < fx {
                        d.step_in_place(x, alpha);
                        fx = f;
                    }
                    self.directions.remove(biggest_at);
                    self.directions.push(d);
                }
            }
        }
        Ok(fx)
    }

    /// Whether an iteration from cost `f0` to `f` lowered it by less than the tolerance (or left
    /// it infinite).
    fn converged(&self, f0: f64, f: f64) -> bool {
        !f.is_finite() || 2.0 * (f0 - f) <= self.tolerance * (f0.abs() + f.abs()) + 1e-300
    }

    /// Minimises `cost` from `x0` by at most `max_iters` iterations, stopping as the argmin
    /// executor would (at convergence or at the cap), and returns the point reached and its
    /// cost. The same iterations as running the solver in an [`argmin::core::Executor`], without
    /// the executor's bookkeeping (per-evaluation counters, state copies): for the many tiny
    /// problems of the local optimiser, where that bookkeeping costs as much as the problem.
    ///
    /// ```
    /// use imesh_optim::Powell;
    /// let quadratic = |x: &Vec<f64>| (x[0] - 1.0).powi(2) + 2.0 * (x[1] + 0.5).powi(2);
    /// let (x, f) = Powell::new(0.1).minimise(quadratic, vec![0.0, 0.0], 50);
    /// assert!((x[0] - 1.0).abs() < 1e-6 && (x[1] + 0.5).abs() < 1e-6 && f < 1e-10);
    /// ```
    pub fn minimise(
        self,
        mut cost: impl FnMut(&Vec<f64>) -> f64,
        x0: Vec<f64>,
        max_iters: u64,
    ) -> (Vec<f64>, f64) {
        let f0 = cost(&x0);
        self.minimise_from(cost, x0, f0, max_iters)
    }

    /// [`Powell::minimise`] from a start whose cost `f0` is already known (one evaluation
    /// fewer: in a block coordinate descent, the caller has it from deciding whether to solve).
    ///
    /// ```
    /// use imesh_optim::Powell;
    /// let quadratic = |x: &Vec<f64>| (x[0] - 1.0).powi(2) + 2.0 * (x[1] + 0.5).powi(2);
    /// let (x, f) = Powell::new(0.1).minimise_from(quadratic, vec![0.0, 0.0], 1.5, 50);
    /// assert!((x[0] - 1.0).abs() < 1e-6 && (x[1] + 0.5).abs() < 1e-6 && f < 1e-10);
    /// ```
    pub fn minimise_from(
        mut self,
        cost: impl FnMut(&Vec<f64>) -> f64,
        x0: Vec<f64>,
        f0: f64,
        max_iters: u64,
    ) -> (Vec<f64>, f64) {
        let mut x = x0;
        let fx = self.minimise_in_place(cost, &mut x, f0, max_iters);
        (x, fx)
    }

    /// [`Powell::minimise_from`] moving `x` in place and returning its cost, with the solver's
    /// work vectors kept for the next call: for many small problems solved one after another,
    /// as the local optimiser's (the initial step is set for each by
    /// [`Powell::set_initial_step`]).
    ///
    /// ```
    /// use imesh_optim::Powell;
    /// let mut powell = Powell::new(0.1);
    /// for target in [1.0, -2.0] {
    ///     let quadratic = |x: &Vec<f64>| (x[0] - target).powi(2) + 2.0 * (x[1] + 0.5).powi(2);
    ///     let mut x = vec![0.0, 0.0];
    ///     let f = powell.minimise_in_place(quadratic, &mut x, quadratic(&vec![0.0, 0.0]), 50);
    ///     assert!((x[0] - target).abs() < 1e-6 && (x[1] + 0.5).abs() < 1e-6 && f < 1e-10);
    /// }
    /// ```
    pub fn minimise_in_place(
        &mut self,
        mut cost: impl FnMut(&Vec<f64>) -> f64,
        x: &mut [f64],
        f0: f64,
        max_iters: u64,
    ) -> f64 {
        let mut cost = |y: &Vec<f64>| -> Result<f64, Infallible> { Ok(cost(y)) };
        let mut fx = f0;
        self.directions.clear();
        self.directions.extend((0..x.len()).map(Direction::Axis));
        let mut previous = f64::INFINITY;
        for iter in 0..max_iters {
            if iter > 0 && self.converged(previous, fx) {
                break;
            }
            let Ok(f) = self.iterate(&mut cost, x, fx);
            (previous, fx) = (fx, f);
        }
        fx
    }

    /// The same solver with first line-search steps of `initial_step` (its work vectors kept).
    #[must_use]
    pub fn with_initial_step(mut self, initial_step: f64) -> Self {
        self.set_initial_step(initial_step);
        self
    }

    /// Sets the first line-search steps to `initial_step` (1 for a step that is not positive
    /// and finite), keeping the work vectors: between the small problems of
    /// [`Powell::minimise_in_place`].
    ///
    /// ```
    /// use imesh_optim::Powell;
    /// let mut powell = Powell::new(0.1);
    /// // A scale a thousand times larger: the first steps follow it.
    /// powell.set_initial_step(100.0);
    /// let mut x = vec![0.0];
    /// let far = |x: &Vec<f64>| (x[0] - 500.0).powi(2);
    /// let f = powell.minimise_in_place(far, &mut x, far(&vec![0.0]), 50);
    /// assert!((x[0] - 500.0).abs() < 1e-3 && f < 1e-6);
    /// ```
    pub fn set_initial_step(&mut self, initial_step: f64) {
        self.initial_step = if initial_step > 0.0 && initial_step.is_finite() {
            initial_step
        } else {
            1.0
        };
    }
}

impl<O> Solver<O, IterState<Vec<f64>, (), (), (), (), f64>> for Powell
where
    O: CostFunction<Param = Vec<f64>, Output = f64>,
{
    fn name(&self) -> &str {
        "Powell"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: IterState<Vec<f64>, (), (), (), (), f64>,
    ) -> Result<(IterState<Vec<f64>, (), (), (), (), f64>, Option<KV>), Error> {
        let x = state
            .get_param()
            .cloned()
            .ok_or_else(|| Error::msg("Powell needs an initial parameter vector"))?;
        let fx = problem.cost(&x)?;
        self.directions = (0..x.len()).map(Direction::Axis).collect();
        Ok((state.param(x).cost(fx), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: IterState<Vec<f64>, (), (), (), (), f64>,
    ) -> Result<(IterState<Vec<f64>, (), (), (), (), f64>, Option<KV>), Error> {
        let mut x = state
            .take_param()
            .ok_or_else(|| Error::msg("Powell lost its parameter vector"))?;
        let f0 = state.get_cost();
        let fx = self.iterate(&mut |x| problem.cost(x), &mut x, f0)?;
        Ok((state.param(x).cost(fx), None))
    }

    fn terminate(&mut self, state: &IterState<Vec<f64>, (), (), (), (), f64>) -> TerminationStatus {
        if state.get_iter() > 0 && self.converged(state.get_prev_cost(), state.get_cost()) {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

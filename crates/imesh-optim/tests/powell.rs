//! Powell's method on the classic test functions, through argmin's executor and directly.

use argmin::core::{CostFunction, Error, Executor, State};
use imesh_optim::Powell;

#[derive(Clone)]
struct Rosenbrock;

impl CostFunction for Rosenbrock {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        Ok((1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2))
    }
}

/// `(x − c)ᵀ A (x − c)` with a dense, badly conditioned positive definite `A`.
#[derive(Clone)]
struct Quadratic {
    a: Vec<Vec<f64>>,
    centre: Vec<f64>,
}

impl Quadratic {
    fn new(n: usize) -> Self {
        // A = Bᵀ B + I with B full: eigenvalues spread over two orders of magnitude.
        let b: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| ((i * 7 + j * 3) % 5) as f64 - 1.5 + if i == j { 4.0 } else { 0.0 })
                    .collect()
            })
            .collect();
        let a = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        (0..n).map(|k| b[k][i] * b[k][j]).sum::<f64>() + f64::from(u8::from(i == j))
                    })
                    .collect()
            })
            .collect();
        let centre = (0..n).map(|i| (i as f64 * 0.7).sin() * 3.0).collect();
        Self { a, centre }
    }
}

impl CostFunction for Quadratic {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        let d: Vec<f64> = x.iter().zip(&self.centre).map(|(x, c)| x - c).collect();
        Ok((0..d.len())
            .map(|i| d[i] * (0..d.len()).map(|j| self.a[i][j] * d[j]).sum::<f64>())
            .sum())
    }
}

/// `(x₀ − 2)² + (x₁ + 1)²`, infinite (infeasible) where `x₀ > 1`.
#[derive(Clone)]
struct Fenced;

impl CostFunction for Fenced {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        if x[0] > 1.0 {
            return Ok(f64::INFINITY);
        }
        Ok((x[0] - 2.0).powi(2) + (x[1] + 1.0).powi(2))
    }
}

#[test]
fn powell_finds_the_rosenbrock_minimum() {
    let result = Executor::new(Rosenbrock, Powell::new(0.5).with_tolerance(1e-14))
        .configure(|s| s.param(vec![-1.2, 1.0]).max_iters(500))
        .run()
        .unwrap();
    let state = result.state();
    let x = state.get_best_param().unwrap();
    assert!(
        (x[0] - 1.0).abs() < 1e-5 && (x[1] - 1.0).abs() < 1e-5,
        "{x:?}"
    );
    assert!(state.get_best_cost() < 1e-10);
}

#[test]
fn powell_solves_a_dense_quadratic_in_few_iterations() {
    // Conjugate directions: an n-dimensional quadratic needs about n iterations, not hundreds.
    let n = 6;
    let q = Quadratic::new(n);
    let centre = q.centre.clone();
    let result = Executor::new(q, Powell::new(1.0).with_tolerance(1e-15))
        .configure(|s| s.param(vec![0.0; n]).max_iters(60))
        .run()
        .unwrap();
    let state = result.state();
    let x = state.get_best_param().unwrap();
    for (a, b) in x.iter().zip(&centre) {
        assert!((a - b).abs() < 1e-5, "{x:?} vs {centre:?}");
    }
    assert!(
        state.get_iter() < 60,
        "took {} iterations",
        state.get_iter()
    );
}

#[test]
fn powell_stays_on_the_feasible_side_of_an_infinite_wall() {
    let result = Executor::new(Fenced, Powell::new(0.3).with_tolerance(1e-14))
        .configure(|s| s.param(vec![0.0, 0.0]).max_iters(100))
        .run()
        .unwrap();
    let state = result.state();
    let x = state.get_best_param().unwrap();
    assert!(x[0] <= 1.0, "left the feasible set: {x:?}");
    assert!(
        (x[0] - 1.0).abs() < 1e-4 && (x[1] + 1.0).abs() < 1e-6,
        "{x:?}"
    );
    assert!(state.get_best_cost().is_finite());
}

#[test]
fn powell_never_returns_a_worse_point_than_the_start() {
    // A start at the minimum: nothing to gain, the start comes back.
    let result = Executor::new(Rosenbrock, Powell::new(0.1))
        .configure(|s| s.param(vec![1.0, 1.0]).max_iters(10))
        .run()
        .unwrap();
    assert_eq!(result.state().get_best_cost(), 0.0);
    assert_eq!(result.state().get_best_param().unwrap(), &vec![1.0, 1.0]);
}

/// Runs `powell` on `problem` from `start` for at most `iterations` both through argmin's
/// executor and through [`Powell::minimise`].
fn both_ways<O>(
    problem: O,
    powell: Powell,
    start: Vec<f64>,
    iterations: u64,
) -> [(Vec<f64>, f64); 2]
where
    O: CostFunction<Param = Vec<f64>, Output = f64> + Clone,
{
    let result = Executor::new(problem.clone(), powell.clone())
        .configure(|s| s.param(start.clone()).max_iters(iterations))
        .run()
        .unwrap();
    let state = result.state();
    let executor = (
        state.get_best_param().unwrap().clone(),
        state.get_best_cost(),
    );
    let direct = powell.minimise(|x| problem.cost(x).unwrap(), start, iterations);
    [executor, direct]
}

#[test]
fn minimise_takes_the_executors_steps_exactly() {
    // The local optimiser relies on it: same iterates, same stopping, bit for bit.
    for iterations in [1, 2, 5, 500] {
        let [a, b] = both_ways(Rosenbrock, Powell::new(0.5), vec![-1.2, 1.0], iterations);
        assert_eq!(a, b, "Rosenbrock, {iterations} iterations");
        let [a, b] = both_ways(
            Quadratic::new(5),
            Powell::new(1.0),
            vec![0.0; 5],
            iterations,
        );
        assert_eq!(a, b, "quadratic, {iterations} iterations");
        let local = Powell::new(0.3)
            .with_tolerance(1e-4)
            .with_line_search(1e-2, 10);
        let [a, b] = both_ways(Fenced, local, vec![0.0, 0.0], iterations);
        assert_eq!(a, b, "fenced, {iterations} iterations");
    }
}

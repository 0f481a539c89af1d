//! Robust nonlinear least squares for the calibration's problems: the
//! Levenberg-Marquardt solver of the `levenberg-marquardt` crate over a
//! residual function, its Jacobian by central differences, and a Huber
//! loss applied as iteratively reweighted least squares over blocks of
//! residuals (a capture's numbers form one block, so a capture paired
//! with the wrong pose loses its weight as a whole).
//!
//! Every problem here is parametrised minimally: a rotation is a small
//! rotation vector applied to a fixed reference rotation (no quaternion
//! norm or matrix orthonormality to keep), a translation or a point its
//! three coordinates.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use lm_nalgebra::{DMatrix as LmMatrix, DVector as LmVector, Dyn, Owned};
use nalgebra::{DMatrix, Rotation3, Vector3};

/// The step of the central differences, in the parameters' own units
/// (radians, millimetres): small against any calibration's scale, large
/// against the rounding of residuals of a few hundred millimetres.
const DIFFERENCE_STEP: f64 = 1e-6;

/// The most reweighting rounds of the Huber loss; the weights settle in
/// three or four.
const MAX_REWEIGHT_ROUNDS: usize = 12;

/// Reweighting stops when no block's weight moved by more than this.
const WEIGHT_SETTLED: f64 = 1e-4;

/// A block whose residual norm is within this multiple of the blocks'
/// median keeps its full weight; beyond it the Huber loss grows linearly,
/// its weight falling as `threshold / norm`.
pub const HUBER_OVER_MEDIAN: f64 = 2.0;

/// Why a refinement gave no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefineError {
    #[error("the residuals are not finite at the starting point")]
    NotFinite,
    #[error("the least-squares solver could not run: {0}")]
    Solver(String),
}

/// A residual function's value at some parameters: its blocks, each a
/// short run of residuals in units of their nominal noise, kept in one
/// buffer (a fit over a sphere's twenty thousand points makes one block
/// per point, many times per iteration).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Blocks {
    values: Vec<f64>,
    /// Where each block starts in `values`.
    starts: Vec<usize>,
}

impl Blocks {
    pub fn with_capacity(blocks: usize, values: usize) -> Blocks {
        Blocks { values: Vec::with_capacity(values), starts: Vec::with_capacity(blocks) }
    }

    /// Appends one block.
    pub fn push(&mut self, block: &[f64]) {
        self.starts.push(self.values.len());
        self.values.extend_from_slice(block);
    }

    pub fn len(&self) -> usize {
        self.starts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }

    /// Block `b`'s residuals.
    pub fn block(&self, b: usize) -> &[f64] {
        let end = self.starts.get(b + 1).copied().unwrap_or(self.values.len());
        &self.values[self.starts[b]..end]
    }

    pub fn iter(&self) -> impl Iterator<Item = &[f64]> {
        (0..self.len()).map(|b| self.block(b))
    }

    /// The same blocks with every value mapped.
    pub fn map_values(&self, f: impl Fn(f64) -> f64) -> Blocks {
        Blocks { values: self.values.iter().map(|v| f(*v)).collect(), starts: self.starts.clone() }
    }
}

impl<B: AsRef<[f64]>> FromIterator<B> for Blocks {
    fn from_iter<I: IntoIterator<Item = B>>(iter: I) -> Self {
        let mut blocks = Blocks::default();
        for b in iter {
            blocks.push(b.as_ref());
        }
        blocks
    }
}

/// A residual function's Jacobian in closed form: one row per residual,
/// one column per parameter.
pub type Jacobian<'a> = &'a dyn Fn(&[f64]) -> DMatrix<f64>;

/// The result of a robust fit.
#[derive(Debug, Clone)]
pub struct RobustFit {
    pub params: Vec<f64>,
    /// Each block's Huber weight at the end, 1 for a block within the
    /// threshold.
    pub weights: Vec<f64>,
}

/// Minimises `Σ w_b ‖r_b(p)‖²` over `p` from `start`, the weights `w_b`
/// of the Huber loss on the block norms recomputed until they settle.
/// The Jacobian is taken by central differences.
pub fn robust_fit(start: &[f64], residuals: &dyn Fn(&[f64]) -> Blocks) -> Result<RobustFit, RefineError> {
    reweighted(start, residuals, None)
}

/// [`robust_fit`] with the residuals' Jacobian in closed form: `jacobian`
/// gives one row per residual, in the blocks' order. A fit over tens of
/// thousands of residuals then evaluates them once per step rather than
/// twice per parameter; the minimum is the same (tests hold the two
/// together).
pub fn robust_fit_with_jacobian(
    start: &[f64],
    residuals: &dyn Fn(&[f64]) -> Blocks,
    jacobian: &dyn Fn(&[f64]) -> DMatrix<f64>,
) -> Result<RobustFit, RefineError> {
    reweighted(start, residuals, Some(jacobian))
}

fn reweighted(
    start: &[f64],
    residuals: &dyn Fn(&[f64]) -> Blocks,
    jacobian: Option<Jacobian<'_>>,
) -> Result<RobustFit, RefineError> {
    let blocks = residuals(start);
    if !blocks.values.iter().all(|r| r.is_finite()) {
        return Err(RefineError::NotFinite);
    }
    let mut weights = vec![1.0; blocks.len()];
    let mut params = start.to_vec();
    for _ in 0..MAX_REWEIGHT_ROUNDS {
        let weighted_residuals = |p: &[f64]| weighted(&residuals(p), &weights);
        params = match jacobian {
            None => least_squares(&params, &weighted_residuals)?,
            Some(jacobian) => {
                // Every block keeps its length whatever the parameters, so
                // each row's weight is known before the solve.
                let row_scale = weighted(&blocks.map_values(|_| 1.0), &weights);
                let weighted_jacobian = |p: &[f64]| {
                    let mut jac = jacobian(p);
                    for (mut row, scale) in jac.row_iter_mut().zip(&row_scale) {
                        row *= *scale;
                    }
                    jac
                };
                solve(&params, &weighted_residuals, Some(&weighted_jacobian))?
            }
        };
        let next = huber_weights(&residuals(&params));
        let moved = weights.iter().zip(&next).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        weights = next;
        if moved < WEIGHT_SETTLED {
            break;
        }
    }
    Ok(RobustFit { params, weights })
}

/// The Huber weights of blocks: 1 up to [`HUBER_OVER_MEDIAN`] times the
/// median norm, `threshold / norm` beyond.
pub fn huber_weights(blocks: &Blocks) -> Vec<f64> {
    let norms: Vec<f64> = blocks.iter().map(norm).collect();
    let threshold = HUBER_OVER_MEDIAN * median(&norms);
    norms.iter().map(|&n| if n <= threshold || n == 0.0 { 1.0 } else { threshold / n }).collect()
}

/// The blocks scaled by the square roots of their weights, as one vector.
pub fn weighted(blocks: &Blocks, weights: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(blocks.values.len());
    for (b, w) in blocks.iter().zip(weights) {
        let scale = w.sqrt();
        out.extend(b.iter().map(|r| r * scale));
    }
    out
}

/// Euclidean norm of a slice.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The median of `values` (the mean of the middle two for an even count);
/// 0 for none.
pub fn median(values: &[f64]) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.is_empty() {
        return 0.0;
    }
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len() % 2 == 1 { sorted[mid] } else { 0.5 * (sorted[mid - 1] + sorted[mid]) }
}

/// Plain (unweighted) Levenberg-Marquardt from `start`.
pub fn least_squares(start: &[f64], residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> Result<Vec<f64>, RefineError> {
    solve(start, residuals, None)
}

/// Levenberg-Marquardt from `start`, with the Jacobian given or by
/// central differences.
fn solve(
    start: &[f64],
    residuals: &dyn Fn(&[f64]) -> Vec<f64>,
    jacobian: Option<Jacobian<'_>>,
) -> Result<Vec<f64>, RefineError> {
    let problem = NumericProblem { params: start.to_vec(), residuals, jacobian };
    let (solved, report) = LevenbergMarquardt::new().minimize(problem);
    if report.termination.was_usage_issue() {
        return Err(RefineError::Solver(format!("{:?}", report.termination)));
    }
    if !report.objective_function.is_finite() {
        return Err(RefineError::NotFinite);
    }
    Ok(solved.params)
}

/// The Jacobian of `residuals` at `params` by central differences, one
/// row per residual.
pub fn jacobian(params: &[f64], residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> DMatrix<f64> {
    let rows = residuals(params).len();
    let mut jac = DMatrix::zeros(rows, params.len());
    let mut probe = params.to_vec();
    for k in 0..params.len() {
        probe[k] = params[k] + DIFFERENCE_STEP;
        let plus = residuals(&probe);
        probe[k] = params[k] - DIFFERENCE_STEP;
        let minus = residuals(&probe);
        probe[k] = params[k];
        for (row, (p, m)) in plus.iter().zip(&minus).enumerate().take(rows) {
            jac[(row, k)] = (p - m) / (2.0 * DIFFERENCE_STEP);
        }
    }
    jac
}

/// The rotation `exp(ω) · reference`: the minimal parametrisation of a
/// rotation near `reference` by the small rotation vector `ω` (radians).
pub fn perturbed(reference: &Rotation3<f64>, omega: &[f64]) -> Rotation3<f64> {
    Rotation3::new(Vector3::new(omega[0], omega[1], omega[2])) * reference
}

/// The crate's view of a residual function: parameters in, residuals and
/// their Jacobian (given, or by central differences) out, in its
/// nalgebra's dynamic vectors.
struct NumericProblem<'a> {
    params: Vec<f64>,
    residuals: &'a dyn Fn(&[f64]) -> Vec<f64>,
    jacobian: Option<Jacobian<'a>>,
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for NumericProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &LmVector<f64>) {
        self.params.copy_from_slice(x.as_slice());
    }

    fn params(&self) -> LmVector<f64> {
        LmVector::from_column_slice(&self.params)
    }

    fn residuals(&self) -> Option<LmVector<f64>> {
        let r = (self.residuals)(&self.params);
        r.iter().all(|v| v.is_finite()).then(|| LmVector::from_vec(r))
    }

    fn jacobian(&self) -> Option<LmMatrix<f64>> {
        let jac = match self.jacobian {
            Some(given) => given(&self.params),
            None => jacobian(&self.params, self.residuals),
        };
        jac.iter().all(|v| v.is_finite()).then(|| LmMatrix::from_column_slice(jac.nrows(), jac.ncols(), jac.as_slice()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_fit_ignores_a_gross_outlier_under_the_huber_loss() {
        // y = 2x + 1 at ten points, one of them 50 off.
        let xs: Vec<f64> = (0..10).map(f64::from).collect();
        let ys: Vec<f64> =
            xs.iter().map(|x| 2.0 * x + 1.0 + if *x == 4.0 { 50.0 } else { 0.01 * (x * 7.0).sin() }).collect();
        let blocks = |p: &[f64]| -> Blocks { xs.iter().zip(&ys).map(|(x, y)| [p[0] * x + p[1] - y]).collect() };
        let plain = least_squares(&[0.0, 0.0], &|p| blocks(p).iter().flatten().copied().collect()).unwrap();
        let robust = robust_fit(&[0.0, 0.0], &blocks).unwrap();
        assert!((plain[1] - 1.0).abs() > 1.0, "the plain fit is pulled: {plain:?}");
        assert!((robust.params[0] - 2.0).abs() < 0.05 && (robust.params[1] - 1.0).abs() < 0.3, "{robust:?}");
        assert!(robust.weights[4] < 0.1 && robust.weights[0] == 1.0, "{:?}", robust.weights);
    }

    #[test]
    fn the_numeric_jacobian_matches_the_derivative() {
        let f = |p: &[f64]| vec![p[0] * p[0] * p[1], p[1].sin()];
        let j = jacobian(&[3.0, 0.5], &f);
        assert!((j[(0, 0)] - 3.0).abs() < 1e-6 && (j[(0, 1)] - 9.0).abs() < 1e-6);
        assert!((j[(1, 1)] - 0.5f64.cos()).abs() < 1e-8 && j[(1, 0)] == 0.0);
    }

    #[test]
    fn medians() {
        assert_eq!(median(&[]), 0.0);
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}

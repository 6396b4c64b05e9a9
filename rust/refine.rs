//! Joint output-error refinement over every experiment (beyond the paper).
//!
//! Minimises `sum_i weight_i ||ybar_i - w_i(beta, gamma, mu, g_i, phi_i)||^2` by
//! Levenberg-Marquardt, where `w_i` is the steady loop of (2b) under `x_i = U_i g_i cos(omega_i t -
//! phi_i)` ([`crate::steady::steady_loop`], exact sensitivities). With `weight_i = N_i / sigma_i^2`
//! (periods averaged over noise variance) the cost is the chi-square of the averaged data and
//! `J^T W J` is the Fisher information.
//!
//! The shared parameters `(beta, gamma, mu)` touch every residual, each `(g_i, phi_i)` only its
//! own: the damped normal equations are solved through the 3x3 Schur complement, so one
//! iteration costs O(m) small solves for m experiments.
//!
//! The Levenberg-Marquardt itself ([`levenberg_marquardt`]) is generic over a [`JointModel`]
//! (shared vector of any size, two own parameters per experiment): the plain model here and the
//! augmented model of design.md 9.3 (`rust/augmented.rs`) share one damping schedule, stopping rules
//! and Schur solve. The experiments are evaluated in parallel and summed in a fixed order.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use rayon::prelude::*;

use crate::error::{all_finite, finite, CoreError, Result};
use crate::steady::{steady_loop, D_AMPLITUDE, D_BETA, D_GAMMA, D_MU, D_PHI};

/// Initial Marquardt damping, relative to the diagonal of `J^T W J`.
const LAMBDA_START: f64 = 1e-3;
/// Damping shrink after an accepted step and growth after a rejected one.
const LAMBDA_DOWN: f64 = 0.2;
const LAMBDA_UP: f64 = 10.0;
/// Damping beyond which no step can decrease the cost: the fit is at a minimum.
const LAMBDA_MAX: f64 = 1e12;
/// Smallest distance kept between mu and its lower limit 1.
const MU_MARGIN: f64 = 1e-9;
/// A constraint whose slack is below this fraction of its terms' size holds the point on its face.
const BOUNDARY_RTOL: f64 = 1e-12;

/// One experiment's averaged period and weight.
#[derive(Debug, Clone, Copy)]
pub struct Experiment<'a> {
    /// Averaged output over one period, length P, sampled at `t_j = j T / P`.
    pub ybar: &'a [f64],
    /// Input amplitude U (non-zero).
    pub amplitude: f64,
    /// Weight of each squared residual, `N / sigma^2` for N averaged periods.
    pub weight: f64,
}

/// Model parameters: shared hysteresis, then per-experiment gain (signed) and phase.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Bouc-Wen beta of (2b).
    pub beta: f64,
    /// Bouc-Wen gamma of (2b).
    pub gamma: f64,
    /// Bouc-Wen exponent mu > 1.
    pub mu: f64,
    /// `g_i` such that `x_i = U_i g_i cos(omega_i t - phi_i)`.
    pub gains: Vec<f64>,
    /// `phi_i` (rad).
    pub phases: Vec<f64>,
}

impl Params {
    /// The flat vector `[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]` (the order of the Fisher
    /// information).
    pub fn flat(&self) -> Vec<f64> {
        let mut v = vec![self.beta, self.gamma, self.mu];
        for (g, p) in self.gains.iter().zip(&self.phases) {
            v.push(*g);
            v.push(*p);
        }
        v
    }

    /// The parameters of `m` experiments from their [`Params::flat`] vector `v`, called `name` in
    /// the error.
    ///
    /// Errors: [`CoreError::InvalidParameter`] unless `v` holds `3 + 2 m` values.
    pub fn from_flat(name: &str, v: &[f64], m: usize) -> Result<Self> {
        if v.len() != 3 + 2 * m {
            return Err(CoreError::InvalidParameter(format!(
                "{name} has {} values; {m} experiments need 3 + 2 * {m} = {}",
                v.len(),
                3 + 2 * m
            )));
        }
        Ok(Self {
            beta: v[0],
            gamma: v[1],
            mu: v[2],
            gains: v[3..].iter().step_by(2).copied().collect(),
            phases: v[4..].iter().step_by(2).copied().collect(),
        })
    }
}

/// Options of the joint fits, [`refine`] and the augmented model's (`rust/augmented.rs`): the stopping
/// rules of [`levenberg_marquardt`], the loop solver's resolution and the mu bracket.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Iteration cap.
    pub max_iter: usize,
    /// RK4 steps per sample interval of the steady loop (per path segment of the path loop).
    pub substeps: usize,
    /// Stop when the relative cost decrease of an accepted step is below this.
    pub ftol: f64,
    /// Stop when every step component is below `xtol * (|p| + xtol)`.
    pub xtol: f64,
    /// Lower end of the admissible mu (exclusive; at least 1).
    pub mu_lo: f64,
    /// Upper end of the admissible mu (inclusive).
    pub mu_hi: f64,
    /// Iterations of the stall window (0: no stall rule). From the second window on, the search stops
    /// at a window's end when the window lowered the cost by at most `stall_rtol` times the cost: the
    /// rule the diagnosis once applied between separate runs of this many iterations, with the damping
    /// carried across the windows instead of restarted at [`LAMBDA_START`] (docs/diagnosis-speed.md,
    /// session 46).
    pub stall_window: usize,
    /// The stall window's relative cost decrease (see `stall_window`).
    pub stall_rtol: f64,
    /// Stop after an accepted step that lowered the cost by at most this fraction of it when the
    /// Gauss-Newton step from the new point predicts no larger decrease either (0: no such rule;
    /// [`StopReason::Stall`]).
    pub step_rtol: f64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            max_iter: 200,
            substeps: 4,
            ftol: 1e-12,
            xtol: 1e-10,
            mu_lo: 1.0,
            mu_hi: f64::INFINITY,
            stall_window: 0,
            stall_rtol: 0.0,
            step_rtol: 0.0,
        }
    }
}

/// Outcome of [`refine`].
#[derive(Debug, Clone)]
pub struct Fit {
    /// The minimiser.
    pub params: Params,
    /// Weighted residual sum of squares at the minimiser.
    pub cost: f64,
    /// Accepted plus rejected LM iterations.
    pub iterations: usize,
    /// Whether a stopping rule other than the iteration cap ended the search.
    pub converged: bool,
    /// The stopping rule that ended the search.
    pub stop: StopReason,
    /// The constraints the minimiser sits on and that hold it there ([`Constraint::name`]).
    pub active: Vec<String>,
    /// `J^T W J` at the minimiser, order `[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]`.
    pub fisher: DMatrix<f64>,
    /// Model loops `w_i` at the minimiser.
    pub loops: Vec<Vec<f64>>,
}

/// Why [`levenberg_marquardt`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// An accepted step decreased the cost by less than `ftol` (relative).
    CostDecrease,
    /// Every component of the step was below `xtol (|p| + xtol)`.
    SmallStep,
    /// The damping grew beyond [`LAMBDA_MAX`]: no step decreases the cost.
    NoDecrease,
    /// The iteration cap `max_iter` (not converged).
    IterationCap,
    /// A stall window (`Options::stall_window`) lowered the cost by at most `stall_rtol` of it, or a
    /// step and the Gauss-Newton prediction from its end by at most `step_rtol` of it.
    Stall,
}

impl StopReason {
    /// The reason's code as Python sees it.
    pub fn code(self) -> &'static str {
        match self {
            StopReason::CostDecrease => "ftol",
            StopReason::SmallStep => "xtol",
            StopReason::NoDecrease => "no_decrease",
            StopReason::IterationCap => "max_iter",
            StopReason::Stall => "stall",
        }
    }
}

/// A closed linear constraint on the shared parameters, `sum_k c_k shared[i_k] >= bound`, on which
/// a joint fit may end. [`levenberg_marquardt`] keeps an active set of them: a step that would cross
/// one lands on it, a step from its face stays on it while its multiplier says it holds the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Constraint {
    /// What holds when it is active, e.g. `"beta=gamma"`, `"mu=lower"`, `"sensor_lag=0"`.
    pub name: String,
    /// Its normal, sparse: `(index into shared, coefficient)`.
    pub normal: Vec<(usize, f64)>,
    /// Its right-hand side.
    pub bound: f64,
}

impl Constraint {
    /// `c . shared - bound` (>= 0 where admissible).
    fn slack(&self, shared: &[f64]) -> f64 {
        self.normal.iter().map(|&(i, c)| c * shared[i]).sum::<f64>() - self.bound
    }

    /// `c . ds`.
    fn dot(&self, ds: &DVector<f64>) -> f64 {
        self.normal.iter().map(|&(i, c)| c * ds[i]).sum()
    }

    /// Slack below which the point is on the face (rounding of `c . shared`).
    fn tol(&self, shared: &[f64]) -> f64 {
        let size = self
            .normal
            .iter()
            .map(|&(i, c)| (c * shared[i]).abs())
            .sum::<f64>();
        BOUNDARY_RTOL * (size + self.bound.abs()).max(f64::MIN_POSITIVE)
    }
}

/// One experiment's model at one point, as the joint Levenberg-Marquardt needs it.
#[derive(Debug, Clone)]
pub struct ModelEval {
    /// The model output on the experiment's grid, length P.
    pub y: Vec<f64>,
    /// `dy_j / d shared`, row-major (P, n_shared).
    pub jac_shared: Vec<f64>,
    /// `dy_j / d(own_0, own_1)`, one row per sample.
    pub jac_own: Vec<[f64; 2]>,
}

/// A per-experiment model whose parameters split into a shared vector (touching every
/// experiment) and two own parameters per experiment, fitted by [`levenberg_marquardt`].
pub trait JointModel: Sync {
    /// Size of the shared vector.
    fn n_shared(&self) -> usize;
    /// Number of experiments m.
    fn n_experiments(&self) -> usize;
    /// Experiment `i`'s data `ybar` (length P) and the weight of each squared residual.
    fn data(&self, i: usize) -> (&[f64], f64);
    /// Experiment `i`'s model output and Jacobian at `(shared, own)`.
    fn evaluate(&self, i: usize, shared: &[f64], own: [f64; 2]) -> Result<ModelEval>;
    /// The closed linear constraints on the shared vector (they may depend on the own parameters).
    fn constraints(&self, own: &[[f64; 2]]) -> Vec<Constraint>;
    /// Moves a trial point onto the closed constraints it crossed (in place): the safety net
    /// behind the active set (rounding, constraints that depend on the own parameters).
    fn project(&self, shared: &mut [f64], own: &[[f64; 2]]);
    /// Whether a (projected) trial point may be evaluated; an inadmissible one is rejected.
    fn admissible(&self, shared: &[f64], own: &[[f64; 2]]) -> bool;
}

/// Outcome of [`levenberg_marquardt`].
#[derive(Debug, Clone)]
pub struct JointFit {
    /// The shared parameters at the minimiser.
    pub shared: Vec<f64>,
    /// Each experiment's own parameters at the minimiser.
    pub own: Vec<[f64; 2]>,
    /// Weighted residual sum of squares at the minimiser.
    pub cost: f64,
    /// Accepted plus rejected LM iterations.
    pub iterations: usize,
    /// Whether a stopping rule other than the iteration cap ended the search.
    pub converged: bool,
    /// The stopping rule that ended the search.
    pub stop: StopReason,
    /// The constraints the minimiser sits on and that hold it there ([`Constraint::name`]).
    pub active: Vec<String>,
    /// `J^T W J` at the minimiser, order `[shared.., own_0 (2), own_1 (2), ...]`.
    pub fisher: DMatrix<f64>,
    /// Model outputs at the minimiser.
    pub outputs: Vec<Vec<f64>>,
}

/// One experiment's contribution to `J^T W J` and `J^T W r` (J of the model output).
struct ExpBlocks {
    cost: f64,
    y: Vec<f64>,
    /// Shared-shared block, row-major (n, n).
    c: Vec<f64>,
    /// Shared part of `J^T W r`.
    gs: Vec<f64>,
    /// Own-own block.
    a: Matrix2<f64>,
    /// Shared-own block, n rows.
    b: Vec<[f64; 2]>,
    /// Own part of `J^T W r`.
    gi: Vector2<f64>,
}

/// The sums of the experiments' blocks at one point.
struct State {
    cost: f64,
    c: DMatrix<f64>,
    gs: DVector<f64>,
    exps: Vec<ExpBlocks>,
}

fn exp_blocks<M: JointModel>(
    model: &M,
    i: usize,
    shared: &[f64],
    own: [f64; 2],
) -> Result<ExpBlocks> {
    let n = model.n_shared();
    let (ybar, weight) = model.data(i);
    let ev = model.evaluate(i, shared, own)?;
    let mut out = ExpBlocks {
        cost: 0.0,
        c: vec![0.0; n * n],
        gs: vec![0.0; n],
        a: Matrix2::zeros(),
        b: vec![[0.0; 2]; n],
        gi: Vector2::zeros(),
        y: Vec::new(),
    };
    let mut sq = 0.0;
    for (j, (&yj, &mj)) in ybar.iter().zip(&ev.y).enumerate() {
        let r = yj - mj;
        sq += r * r;
        let js = &ev.jac_shared[j * n..(j + 1) * n];
        let jl = Vector2::new(ev.jac_own[j][0], ev.jac_own[j][1]);
        let wr = weight * r;
        for (k, &jk) in js.iter().enumerate() {
            let wk = weight * jk;
            for (c, &jl_) in out.c[k * n..(k + 1) * n].iter_mut().zip(js) {
                *c += wk * jl_;
            }
            out.gs[k] += wr * jk;
            out.b[k][0] += wk * jl[0];
            out.b[k][1] += wk * jl[1];
        }
        out.a += weight * jl * jl.transpose();
        out.gi += wr * jl;
    }
    out.cost = weight * sq;
    out.y = ev.y;
    Ok(out)
}

/// Every experiment evaluated in parallel, the sums formed in experiment order, so the result is
/// bit-identical whatever the number of threads. The first failing experiment's error wins.
fn evaluate_all<M: JointModel>(model: &M, shared: &[f64], own: &[[f64; 2]]) -> Result<State> {
    // One experiment per task (issue 18 item 4): rayon's default halves would leave one thread the
    // three largest grids of the MR damper (P = 401, 391, 401 of 401 ... 37) while the other idles.
    let per: Vec<Result<ExpBlocks>> = (0..model.n_experiments())
        .into_par_iter()
        .with_max_len(1)
        .map(|i| exp_blocks(model, i, shared, own[i]))
        .collect();
    let n = model.n_shared();
    let mut st = State {
        cost: 0.0,
        c: DMatrix::zeros(n, n),
        gs: DVector::zeros(n),
        exps: Vec::with_capacity(per.len()),
    };
    for e in per {
        let e = e?;
        st.cost += e.cost;
        for k in 0..n {
            for l in 0..n {
                st.c[(k, l)] += e.c[k * n + l];
            }
            st.gs[k] += e.gs[k];
        }
        st.exps.push(e);
    }
    Ok(st)
}

/// The damped normal equations reduced to the shared block: the Schur complement `s` of the
/// per-experiment 2x2 blocks, its right-hand side, and the blocks' damped inverses.
struct Reduced {
    s: DMatrix<f64>,
    rhs: DVector<f64>,
    a_inv: Vec<Matrix2<f64>>,
}

fn reduce(st: &State, lambda: f64) -> Option<Reduced> {
    let n = st.gs.len();
    let mut s = st.c.clone();
    for k in 0..n {
        s[(k, k)] += lambda * st.c[(k, k)].max(f64::MIN_POSITIVE);
    }
    let mut rhs = st.gs.clone();
    let mut a_inv = Vec::with_capacity(st.exps.len());
    for e in &st.exps {
        let mut a = e.a;
        for k in 0..2 {
            a[(k, k)] += lambda * e.a[(k, k)].max(f64::MIN_POSITIVE);
        }
        let inv = a.try_inverse()?;
        // B A^-1, n x 2.
        let ba: Vec<[f64; 2]> =
            e.b.iter()
                .map(|r| {
                    [
                        r[0] * inv[(0, 0)] + r[1] * inv[(1, 0)],
                        r[0] * inv[(0, 1)] + r[1] * inv[(1, 1)],
                    ]
                })
                .collect();
        for k in 0..n {
            for l in 0..n {
                s[(k, l)] -= ba[k][0] * e.b[l][0] + ba[k][1] * e.b[l][1];
            }
            rhs[k] -= ba[k][0] * e.gi[0] + ba[k][1] * e.gi[1];
        }
        a_inv.push(inv);
    }
    Some(Reduced { s, rhs, a_inv })
}

/// Each experiment's own step given the shared step `ds` (back substitution).
fn own_steps(st: &State, red: &Reduced, ds: &DVector<f64>) -> Vec<Vector2<f64>> {
    st.exps
        .iter()
        .zip(&red.a_inv)
        .map(|(e, inv)| {
            let mut v = e.gi;
            for (k, d) in ds.iter().enumerate() {
                v[0] -= e.b[k][0] * d;
                v[1] -= e.b[k][1] * d;
            }
            inv * v
        })
        .collect()
}

/// The shared step minimising the damped quadratic model `ds' rhs - ds' s ds / 2` subject to
/// `c_k . ds = target_k` for every `(k, target_k)` of `work`, and the constraints' multipliers
/// (>= 0: the constraint holds the step; < 0: the model would leave the face inwards).
fn face_step(
    red: &Reduced,
    cons: &[Constraint],
    work: &[(usize, f64)],
) -> Option<(DVector<f64>, Vec<f64>)> {
    if work.is_empty() {
        return Some((red.s.clone().cholesky()?.solve(&red.rhs), Vec::new()));
    }
    let (n, w) = (red.rhs.len(), work.len());
    let mut kkt = DMatrix::zeros(n + w, n + w);
    kkt.view_mut((0, 0), (n, n)).copy_from(&red.s);
    let mut b = DVector::zeros(n + w);
    b.rows_mut(0, n).copy_from(&red.rhs);
    for (r, &(k, target)) in work.iter().enumerate() {
        for &(i, c) in &cons[k].normal {
            kkt[(n + r, i)] = c;
            kkt[(i, n + r)] = c;
        }
        b[n + r] = target;
    }
    let sol = kkt.lu().solve(&b)?;
    if !sol.iter().all(|v| v.is_finite()) {
        return None;
    }
    let nu = (0..w).map(|r| -sol[n + r]).collect();
    Some((sol.rows(0, n).into_owned(), nu))
}

/// A step: the shared part, each experiment's own part, and the working set it was solved on.
type ConstrainedStep = (DVector<f64>, Vec<Vector2<f64>>, Vec<usize>);

/// A damped step that respects `cons` (the active set, design.md 7.4): the constraints on whose
/// face `shared` sits start in the working set; one with a negative multiplier is released, the
/// first one the step would cross is added with the target of landing on its face, and the step is
/// re-solved on the working set until neither happens (at most `2 len + 2` solves). Returns the
/// shared and own steps and the working set (indices into `cons`).
fn constrained_step(
    st: &State,
    lambda: f64,
    shared: &[f64],
    cons: &[Constraint],
) -> Option<ConstrainedStep> {
    let red = reduce(st, lambda)?;
    let slack: Vec<f64> = cons.iter().map(|c| c.slack(shared)).collect();
    let tol: Vec<f64> = cons.iter().map(|c| c.tol(shared)).collect();
    let mut work: Vec<usize> = (0..cons.len()).filter(|&k| slack[k] <= tol[k]).collect();
    let mut best = None;
    for _ in 0..2 * cons.len() + 2 {
        let targets: Vec<(usize, f64)> = work.iter().map(|&k| (k, -slack[k])).collect();
        let Some((ds, nu)) = face_step(&red, cons, &targets) else {
            // Dependent faces: keep the last solvable working set (the projection finishes).
            work.pop()?;
            continue;
        };
        let scale = red.rhs.amax().max(f64::MIN_POSITIVE);
        let release = nu
            .iter()
            .enumerate()
            .filter(|&(_, &v)| v < -1e-12 * scale)
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(r, _)| r);
        if let Some(r) = release {
            best = Some((ds, work.clone()));
            work.remove(r);
            continue;
        }
        // The first face the step crosses (smallest fraction of the step that reaches it).
        let cross = (0..cons.len())
            .filter(|k| !work.contains(k))
            .filter_map(|k| {
                let d = cons[k].dot(&ds);
                (slack[k] + d < -tol[k]).then(|| (k, slack[k].max(0.0) / -d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k);
        match cross {
            Some(k) => {
                best = Some((ds, work.clone()));
                work.push(k);
            }
            None => {
                best = Some((ds, work));
                break;
            }
        }
    }
    let (ds, work) = best?;
    let dl = own_steps(st, &red, &ds);
    Some((ds, dl, work))
}

/// The constraints of `work` the point sits on (the face that holds the fit), by name.
fn active_names(cons: &[Constraint], work: &[usize], shared: &[f64]) -> Vec<String> {
    let mut names: Vec<String> = work
        .iter()
        .filter(|&&k| cons[k].slack(shared) <= cons[k].tol(shared))
        .map(|&k| cons[k].name.clone())
        .collect();
    names.sort();
    names
}

fn fisher(st: &State) -> DMatrix<f64> {
    let n = st.gs.len();
    let m = st.exps.len();
    let mut f = DMatrix::zeros(n + 2 * m, n + 2 * m);
    f.view_mut((0, 0), (n, n)).copy_from(&st.c);
    for (i, e) in st.exps.iter().enumerate() {
        let o = n + 2 * i;
        f.view_mut((o, o), (2, 2)).copy_from(&e.a);
        for k in 0..n {
            for l in 0..2 {
                f[(k, o + l)] = e.b[k][l];
                f[(o + l, k)] = e.b[k][l];
            }
        }
    }
    f
}

/// Damping of the Gauss-Newton step whose predicted decrease [`predicted_decrease`] reads.
const GN_LAMBDA: f64 = 1e-12;

/// The decrease of the cost that the (barely damped) Gauss-Newton step from `st` predicts, `d . J'Wr`
/// on the faces that hold the point; infinite where that step cannot be solved.
fn predicted_decrease(st: &State, shared: &[f64], cons: &[Constraint]) -> f64 {
    constrained_step(st, GN_LAMBDA, shared, cons).map_or(f64::INFINITY, |(ds, dl, _)| {
        ds.dot(&st.gs)
            + dl.iter()
                .zip(&st.exps)
                .map(|(d, e)| d.dot(&e.gi))
                .sum::<f64>()
    })
}

/// Levenberg-Marquardt with Marquardt scaling over every experiment of `model` (design.md 7.4,
/// 9.3): damping `lambda diag(J'WJ)` from [`LAMBDA_START`], times [`LAMBDA_DOWN`] on success and
/// [`LAMBDA_UP`] on failure, a minimum once it exceeds [`LAMBDA_MAX`]. The steps respect the model's
/// closed constraints through an active set ([`constrained_step`]): a step that would cross a face
/// lands on it, and a fit on a face moves along it (a Gauss-Newton step in the free subspace) until
/// the face's multiplier says that the cost decreases inwards. So a fit the data pull beyond the
/// admissible set stops on its boundary by the usual rules, and says on which face
/// ([`JointFit::active`]). Trial points are then projected by the model (rounding, faces that move
/// with the own parameters) and rejected when inadmissible or when the model fails there. The
/// experiments are evaluated in parallel (rayon) and reduced in a fixed order.
///
/// Errors: only those of the model at the start point (callers validate the start first).
pub fn levenberg_marquardt<M: JointModel>(
    model: &M,
    shared0: &[f64],
    own0: &[[f64; 2]],
    opts: &Options,
) -> Result<JointFit> {
    let mut shared = shared0.to_vec();
    let mut own = own0.to_vec();
    let mut st = evaluate_all(model, &shared, &own)?;
    let mut lambda = LAMBDA_START;
    let mut iterations = 0;
    let mut stop = StopReason::IterationCap;
    let mut window_cost = st.cost;
    while iterations < opts.max_iter {
        crate::cancel::checkpoint()?;
        if opts.stall_window > 0 && iterations > 0 && iterations % opts.stall_window == 0 {
            if iterations > opts.stall_window && window_cost - st.cost <= opts.stall_rtol * st.cost
            {
                stop = StopReason::Stall;
                break;
            }
            window_cost = st.cost;
        }
        iterations += 1;
        let cons = model.constraints(&own);
        let Some((ds, dl, _)) = constrained_step(&st, lambda, &shared, &cons) else {
            lambda *= LAMBDA_UP;
            if lambda > LAMBDA_MAX {
                stop = StopReason::NoDecrease;
                break;
            }
            continue;
        };
        let mut t_shared: Vec<f64> = shared.iter().zip(ds.iter()).map(|(p, d)| p + d).collect();
        let t_own: Vec<[f64; 2]> = own
            .iter()
            .zip(&dl)
            .map(|(p, d)| [p[0] + d[0], p[1] + d[1]])
            .collect();
        let within = |d: f64, v: f64| d.abs() <= opts.xtol * (v.abs() + opts.xtol);
        let small = ds.iter().zip(&shared).all(|(&d, &v)| within(d, v))
            && dl
                .iter()
                .zip(&own)
                .all(|(d, v)| within(d[0], v[0]) && within(d[1], v[1]));
        model.project(&mut t_shared, &t_own);
        let trial = if model.admissible(&t_shared, &t_own) {
            evaluate_all(model, &t_shared, &t_own).ok()
        } else {
            None
        };
        match trial {
            Some(tst) if tst.cost <= st.cost => {
                let decrease = (st.cost - tst.cost) / st.cost.max(f64::MIN_POSITIVE);
                let lowered = st.cost - tst.cost;
                shared = t_shared;
                own = t_own;
                st = tst;
                lambda = (lambda * LAMBDA_DOWN).max(1e-15);
                if decrease < opts.ftol || small {
                    stop = if small {
                        StopReason::SmallStep
                    } else {
                        StopReason::CostDecrease
                    };
                    break;
                }
                let bound = opts.step_rtol * st.cost;
                if lowered <= bound
                    && predicted_decrease(&st, &shared, &model.constraints(&own)) <= bound
                {
                    stop = StopReason::Stall;
                    break;
                }
            }
            _ => {
                if small {
                    stop = StopReason::SmallStep;
                    break;
                }
                lambda *= LAMBDA_UP;
                if lambda > LAMBDA_MAX {
                    stop = StopReason::NoDecrease;
                    break;
                }
            }
        }
    }
    // The faces that hold the minimiser: the working set of a step from it (the damping only
    // shortens the step; the multipliers' signs are those of the gradient against the faces).
    let cons = model.constraints(&own);
    let active = constrained_step(&st, lambda.min(LAMBDA_MAX), &shared, &cons)
        .or_else(|| constrained_step(&st, LAMBDA_START, &shared, &cons))
        .map_or_else(Vec::new, |(_, _, work)| active_names(&cons, &work, &shared));
    Ok(JointFit {
        fisher: fisher(&st),
        cost: st.cost,
        outputs: st.exps.into_iter().map(|e| e.y).collect(),
        shared,
        own,
        iterations,
        converged: stop != StopReason::IterationCap,
        stop,
        active,
    })
}

/// The plain model of 7.4: `w_i` the steady loop of (2b), shared `[beta, gamma, mu]`, own
/// `[g_i, phi_i]`.
struct PlainModel<'a> {
    exps: &'a [Experiment<'a>],
    opts: &'a Options,
}

impl JointModel for PlainModel<'_> {
    fn n_shared(&self) -> usize {
        3
    }

    fn n_experiments(&self) -> usize {
        self.exps.len()
    }

    fn data(&self, i: usize) -> (&[f64], f64) {
        (self.exps[i].ybar, self.exps[i].weight)
    }

    fn evaluate(&self, i: usize, shared: &[f64], own: [f64; 2]) -> Result<ModelEval> {
        let e = &self.exps[i];
        let l = steady_loop(
            e.amplitude * own[0],
            shared[0],
            shared[1],
            shared[2],
            own[1],
            e.ybar.len(),
            self.opts.substeps,
        )?;
        let mut jac_shared = Vec::with_capacity(3 * l.w.len());
        for r in &l.jac {
            jac_shared.extend_from_slice(&[r[D_BETA], r[D_GAMMA], r[D_MU]]);
        }
        let jac_own = l
            .jac
            .iter()
            .map(|r| [r[D_AMPLITUDE] * e.amplitude, r[D_PHI]])
            .collect();
        Ok(ModelEval {
            y: l.w,
            jac_shared,
            jac_own,
        })
    }

    fn constraints(&self, _own: &[[f64; 2]]) -> Vec<Constraint> {
        hysteresis_constraints(self.opts.mu_lo, self.opts.mu_hi)
    }

    fn project(&self, shared: &mut [f64], _own: &[[f64; 2]]) {
        project_hysteresis(shared, self.opts.mu_lo, self.opts.mu_hi);
    }

    fn admissible(&self, shared: &[f64], _own: &[[f64; 2]]) -> bool {
        hysteresis_admissible(shared, self.opts.mu_lo, self.opts.mu_hi)
    }
}

/// The Bouc-Wen conditions of (2a) (`beta + gamma > 0`, `beta >= gamma`) and the mu bracket, on
/// `shared[..3] = [beta, gamma, mu]`.
pub(crate) fn hysteresis_admissible(shared: &[f64], mu_lo: f64, mu_hi: f64) -> bool {
    let (beta, gamma, mu) = (shared[0], shared[1], shared[2]);
    mu > mu_lo.max(1.0) + MU_MARGIN && mu <= mu_hi && beta + gamma > 0.0 && beta >= gamma
}

/// The closed constraints of `[beta, gamma, mu, ..]` (the faces of [`project_hysteresis`]): `beta >=
/// gamma` ("beta=gamma"), `mu >= mu_lo + 2 MU_MARGIN` ("mu=lower"), and `mu <= mu_hi` ("mu=upper") when
/// finite. `beta + gamma > 0` is open (no loop on its face): trial points beyond it are rejected.
pub(crate) fn hysteresis_constraints(mu_lo: f64, mu_hi: f64) -> Vec<Constraint> {
    let mu_min = mu_lo.max(1.0) + 2.0 * MU_MARGIN;
    let mut cons = vec![
        Constraint {
            name: "beta=gamma".into(),
            normal: vec![(0, 1.0), (1, -1.0)],
            bound: 0.0,
        },
        Constraint {
            name: "mu=lower".into(),
            normal: vec![(2, 1.0)],
            bound: mu_min,
        },
    ];
    if mu_hi.is_finite() {
        cons.push(Constraint {
            name: "mu=upper".into(),
            normal: vec![(2, -1.0)],
            bound: -mu_hi.max(mu_min),
        });
    }
    cons
}

/// Projects a trial point onto the closed constraints it crossed, so that the fit can slide along
/// `beta = gamma` or a bracket end instead of stalling at the first contact: `beta < gamma` becomes
/// `beta = gamma = (beta + gamma) / 2` (the nearest point of the plane, same `beta + gamma`), and `mu`
/// is clipped into the bracket. `beta + gamma <= 0` has no nearest admissible point and stays rejected.
pub(crate) fn project_hysteresis(shared: &mut [f64], mu_lo: f64, mu_hi: f64) {
    if shared[0] < shared[1] {
        let mid = 0.5 * (shared[0] + shared[1]);
        shared[0] = mid;
        shared[1] = mid;
    }
    let mu_min = mu_lo.max(1.0) + 2.0 * MU_MARGIN;
    if shared[2].is_finite() {
        shared[2] = shared[2].clamp(mu_min, mu_hi.max(mu_min));
    }
}

/// The checks every joint fit makes before it starts, in order: at least one experiment, one gain
/// and one phase per experiment, each experiment's data finite, its excitation valid
/// (`excitation(i)`) and its weight finite and > 0, the gains and phases finite, and
/// `max_iter`, `substeps >= 1`. The model's own checks (start point, bracket) follow.
///
/// Errors: [`CoreError::InsufficientData`], [`CoreError::NonFinite`],
/// [`CoreError::InvalidParameter`], and those of `excitation`.
pub(crate) fn check_joint_start(
    model: &impl JointModel,
    excitation: impl Fn(usize) -> Result<()>,
    (gains, phases): (&[f64], &[f64]),
    opts: &Options,
) -> Result<()> {
    let m = model.n_experiments();
    if m == 0 {
        return Err(CoreError::InsufficientData(
            "the refinement needs at least one experiment".into(),
        ));
    }
    if gains.len() != m || phases.len() != m {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} gains and {} phases",
            gains.len(),
            phases.len()
        )));
    }
    for i in 0..m {
        let (ybar, weight) = model.data(i);
        all_finite(&format!("ybar[{i}]"), ybar)?;
        excitation(i)?;
        finite("weight", weight)?;
        if weight <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "experiment {i}: weight {weight} must be > 0 (N / noise variance)"
            )));
        }
    }
    all_finite("gains", gains)?;
    all_finite("phases", phases)?;
    if opts.max_iter == 0 || opts.substeps == 0 {
        return Err(CoreError::InvalidParameter(
            "max_iter and substeps must be >= 1".into(),
        ));
    }
    Ok(())
}

fn validate(model: &PlainModel, p: &Params, opts: &Options) -> Result<()> {
    let amplitude = |i: usize| finite("amplitude", model.exps[i].amplitude).map(|_| ());
    check_joint_start(model, amplitude, (&p.gains, &p.phases), opts)?;
    check_start_point(&[p.beta, p.gamma, p.mu], opts)
}

/// Checks that a start `[beta, gamma, mu, ..]` satisfies the Bouc-Wen conditions and the mu
/// bracket (see [`hysteresis_admissible`]).
///
/// Errors: [`CoreError::InvalidParameter`].
pub(crate) fn check_start_point(shared: &[f64], opts: &Options) -> Result<()> {
    if !hysteresis_admissible(shared, opts.mu_lo, opts.mu_hi) {
        return Err(CoreError::InvalidParameter(format!(
            "the starting point (beta = {}, gamma = {}, mu = {}) must satisfy beta >= |gamma|, \
             beta + gamma > 0 and {} < mu <= {}",
            shared[0],
            shared[1],
            shared[2],
            opts.mu_lo.max(1.0),
            opts.mu_hi
        )));
    }
    Ok(())
}

/// Levenberg-Marquardt from `start` (e.g. the profile-phase SLS estimates).
///
/// Every trial point must satisfy the Bouc-Wen conditions and the mu bracket (see `hysteresis_admissible`): a
/// step that crosses `beta = gamma` or a bracket end is projected back onto it (see `project_hysteresis`), one
/// that makes `beta + gamma <= 0` is rejected and the damping grows. So the fit stays admissible and
/// may end on a constraint.
///
/// Errors: an inadmissible start, the start is not a valid loop (see [`steady_loop`]), inconsistent
/// lengths, non-finite data, a non-positive weight.
pub fn refine(exps: &[Experiment], start: &Params, opts: &Options) -> Result<Fit> {
    let model = PlainModel { exps, opts };
    validate(&model, start, opts)?;
    let own: Vec<[f64; 2]> = start
        .gains
        .iter()
        .zip(&start.phases)
        .map(|(&g, &p)| [g, p])
        .collect();
    let fit = levenberg_marquardt(&model, &[start.beta, start.gamma, start.mu], &own, opts)?;
    Ok(Fit {
        params: Params {
            beta: fit.shared[0],
            gamma: fit.shared[1],
            mu: fit.shared[2],
            gains: fit.own.iter().map(|o| o[0]).collect(),
            phases: fit.own.iter().map(|o| o[1]).collect(),
        },
        cost: fit.cost,
        iterations: fit.iterations,
        converged: fit.converged,
        stop: fit.stop,
        active: fit.active,
        fisher: fit.fisher,
        loops: fit.outputs,
    })
}

/// Unit-weight experiments of the loops `ys` at the input amplitudes `amps` (the tests' problems).
#[cfg(test)]
pub(crate) fn unit_experiments<'a>(ys: &'a [Vec<f64>], amps: &[f64]) -> Vec<Experiment<'a>> {
    ys.iter()
        .zip(amps)
        .map(|(y, &amplitude)| Experiment {
            ybar: y,
            amplitude,
            weight: 1.0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(a: f64, beta: f64, gamma: f64, mu: f64, phi: f64, p: usize) -> Vec<f64> {
        steady_loop(a, beta, gamma, mu, phi, p, 8).unwrap().w
    }

    #[test]
    fn a_stall_window_stops_where_one_uninterrupted_run_would_be() {
        let (beta, gamma, mu) = (0.8, 0.2, 1.6);
        let amps = [2.0, 1.0];
        let ys: Vec<Vec<f64>> = (0..2)
            .map(|i| {
                let w = data(amps[i] * 0.9, beta, gamma, mu, 1.1 + i as f64, 64);
                // a loop the model cannot draw exactly: the fit crawls instead of converging
                w.iter()
                    .enumerate()
                    .map(|(j, v)| v + 0.05 * ((3 * j) as f64 * 0.0981).sin())
                    .collect()
            })
            .collect();
        let exps = unit_experiments(&ys, &amps);
        // [beta, gamma, mu, g_0, phi_0, g_1, phi_1]
        let start = Params::from_flat("start", &[0.6, 0.1, 2.2, 0.8, 1.3, 1.0, 1.9], 2).unwrap();
        let capped = |max_iter, stall_window, stall_rtol| {
            let opts = Options {
                max_iter,
                substeps: 4,
                stall_window,
                stall_rtol,
                ..Options::default()
            };
            refine(&exps, &start, &opts).unwrap()
        };
        // rtol 1: the second window's end always stops the fit, at one 8-iteration run's point
        let stalled = capped(40, 4, 1.0);
        let whole = capped(8, 0, 0.0);
        assert_eq!(stalled.stop, StopReason::Stall);
        assert!(stalled.converged);
        assert_eq!(stalled.iterations, 8);
        assert_eq!(whole.stop, StopReason::IterationCap);
        assert_eq!(stalled.params, whole.params);
        assert_eq!(stalled.cost, whole.cost);
        // rtol 0: a window that lowers the cost at all goes on
        let on = capped(12, 4, 0.0);
        assert_eq!(on.stop, StopReason::IterationCap);
        assert_eq!(on.params, capped(12, 0, 0.0).params);
    }

    #[test]
    fn recovers_exact_parameters_from_a_perturbed_start() {
        let (beta, gamma, mu) = (0.8, 0.2, 1.6);
        let amps = [2.0, 1.0];
        let gains = [0.9, 1.3];
        let phases = [1.1, 2.0];
        let ys: Vec<Vec<f64>> = (0..2)
            .map(|i| data(amps[i] * gains[i], beta, gamma, mu, phases[i], 128))
            .collect();
        let exps: Vec<Experiment> = (0..2)
            .map(|i| Experiment {
                ybar: &ys[i],
                amplitude: amps[i],
                weight: 1.0,
            })
            .collect();
        let start = Params {
            beta: 0.7,
            gamma: 0.3,
            mu: 1.8,
            gains: vec![0.85, 1.4],
            phases: vec![1.05, 2.1],
        };
        let opts = Options {
            substeps: 8,
            ..Options::default()
        };
        let fit = refine(&exps, &start, &opts).unwrap();
        assert!(fit.converged);
        assert!((fit.params.beta - beta).abs() < 1e-7, "{:?}", fit.params);
        assert!((fit.params.gamma - gamma).abs() < 1e-7);
        assert!((fit.params.mu - mu).abs() < 1e-7);
        for i in 0..2 {
            assert!((fit.params.gains[i] - gains[i]).abs() < 1e-7);
            assert!((fit.params.phases[i] - phases[i]).abs() < 1e-7);
        }
        assert!(fit.cost < 1e-20);
        assert_eq!(fit.fisher.nrows(), 7);
        // The Fisher matrix is symmetric positive definite at a well-posed fit.
        assert!(fit.fisher.clone().cholesky().is_some());
    }

    #[test]
    fn a_fit_pulled_beyond_beta_ge_gamma_stops_on_the_face_and_names_it() {
        // Loops plus a strong spring on the measured input (in phase with u, not with x): the plain
        // model cannot draw them and its fit runs into beta = gamma. The projected LM crawled along it
        // to the cap; the active set stops on it by ftol/xtol, with the face named.
        let amps = [1.8, 1.2, 2.4];
        let phases = [1.1, 2.5, 0.4];
        let p = 48;
        let ys: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                let w = data(amps[i], 0.8, 0.2, 1.6, phases[i], p);
                (0..p)
                    .map(|j| {
                        let th = 2.0 * std::f64::consts::PI * j as f64 / p as f64;
                        // Deterministic pseudo-noise so that the fit does not end at zero cost.
                        w[j] + 1.5 * th.cos() + 1e-2 * ((j * 7 + i * 13) as f64).sin()
                    })
                    .collect()
            })
            .collect();
        let exps: Vec<Experiment> = (0..3)
            .map(|i| Experiment {
                ybar: &ys[i],
                amplitude: amps[i],
                weight: 1e4,
            })
            .collect();
        let start = Params {
            beta: 0.7,
            gamma: 0.3,
            mu: 1.7,
            gains: vec![0.9, 1.2, 1.0],
            phases: vec![1.05, 2.45, 0.4],
        };
        let opts = Options {
            substeps: 3,
            ..Options::default()
        };
        let fit = refine(&exps, &start, &opts).unwrap();
        assert!(fit.converged, "{:?} after {}", fit.stop, fit.iterations);
        assert!(matches!(
            fit.stop,
            StopReason::CostDecrease | StopReason::SmallStep
        ));
        assert!(fit.iterations < 100, "{}", fit.iterations);
        assert!(
            fit.active.iter().any(|a| a == "beta=gamma"),
            "{:?}",
            fit.active
        );
        assert!((fit.params.beta - fit.params.gamma).abs() <= 1e-12 * fit.params.beta.abs());
    }

    #[test]
    fn rejects_inconsistent_input() {
        let y = vec![0.0; 16];
        let exps = [Experiment {
            ybar: &y,
            amplitude: 1.0,
            weight: 0.0,
        }];
        let start = Params {
            beta: 0.5,
            gamma: 0.1,
            mu: 1.5,
            gains: vec![1.0],
            phases: vec![0.0],
        };
        assert!(matches!(
            refine(&exps, &start, &Options::default()),
            Err(CoreError::InvalidParameter(_))
        ));
        let start2 = Params {
            gains: vec![],
            ..start
        };
        assert!(refine(&exps, &start2, &Options::default()).is_err());
    }
}

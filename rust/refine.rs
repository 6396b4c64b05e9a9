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
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use nalgebra::{DMatrix, Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

use crate::error::{all_finite, finite, CoreError, Result};
use crate::steady::{steady_loop, SteadyLoop, D_AMPLITUDE, D_BETA, D_GAMMA, D_MU, D_PHI};

/// Initial Marquardt damping, relative to the diagonal of `J^T W J`.
const LAMBDA_START: f64 = 1e-3;
/// Damping shrink after an accepted step and growth after a rejected one.
const LAMBDA_DOWN: f64 = 0.2;
const LAMBDA_UP: f64 = 10.0;
/// Damping beyond which no step can decrease the cost: the fit is at a minimum.
const LAMBDA_MAX: f64 = 1e12;
/// Smallest distance kept between mu and its lower limit 1.
const MU_MARGIN: f64 = 1e-9;

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

/// Stopping rules of [`refine`].
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Iteration cap.
    pub max_iter: usize,
    /// RK4 steps per sample interval of the steady-loop solver.
    pub substeps: usize,
    /// Stop when the relative cost decrease of an accepted step is below this.
    pub ftol: f64,
    /// Stop when every step component is below `xtol * (|p| + xtol)`.
    pub xtol: f64,
    /// Lower end of the admissible mu (exclusive; at least 1).
    pub mu_lo: f64,
    /// Upper end of the admissible mu (inclusive).
    pub mu_hi: f64,
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
    /// `J^T W J` at the minimiser, order `[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]`.
    pub fisher: DMatrix<f64>,
    /// Model loops `w_i` at the minimiser.
    pub loops: Vec<Vec<f64>>,
}

struct Eval {
    cost: f64,
    loops: Vec<SteadyLoop>,
    resid: Vec<Vec<f64>>,
}

fn evaluate(exps: &[Experiment], p: &Params, substeps: usize) -> Result<Eval> {
    let mut cost = 0.0;
    let mut loops = Vec::with_capacity(exps.len());
    let mut resid = Vec::with_capacity(exps.len());
    for (i, e) in exps.iter().enumerate() {
        let l = steady_loop(
            e.amplitude * p.gains[i],
            p.beta,
            p.gamma,
            p.mu,
            p.phases[i],
            e.ybar.len(),
            substeps,
        )?;
        let r: Vec<f64> = e.ybar.iter().zip(&l.w).map(|(y, w)| y - w).collect();
        cost += e.weight * r.iter().map(|v| v * v).sum::<f64>();
        loops.push(l);
        resid.push(r);
    }
    Ok(Eval { cost, loops, resid })
}

/// Per-experiment blocks of `J^T W J` and `J^T W r` (J of the model `w`).
struct Blocks {
    c: Matrix3<f64>,
    gs: Vector3<f64>,
    a: Vec<Matrix2<f64>>,
    b: Vec<Matrix3x2<f64>>,
    gi: Vec<Vector2<f64>>,
}

fn blocks(exps: &[Experiment], ev: &Eval) -> Blocks {
    let m = exps.len();
    let mut out = Blocks {
        c: Matrix3::zeros(),
        gs: Vector3::zeros(),
        a: Vec::with_capacity(m),
        b: Vec::with_capacity(m),
        gi: Vec::with_capacity(m),
    };
    for (i, e) in exps.iter().enumerate() {
        let (mut a, mut b, mut g) = (Matrix2::zeros(), Matrix3x2::zeros(), Vector2::zeros());
        for (row, &r) in ev.loops[i].jac.iter().zip(&ev.resid[i]) {
            let js = Vector3::new(row[D_BETA], row[D_GAMMA], row[D_MU]);
            let jl = Vector2::new(row[D_AMPLITUDE] * e.amplitude, row[D_PHI]);
            out.c += e.weight * js * js.transpose();
            out.gs += e.weight * r * js;
            a += e.weight * jl * jl.transpose();
            b += e.weight * js * jl.transpose();
            g += e.weight * r * jl;
        }
        out.a.push(a);
        out.b.push(b);
        out.gi.push(g);
    }
    out
}

/// Damped Gauss-Newton step through the Schur complement of the per-experiment blocks.
fn step(bl: &Blocks, lambda: f64) -> Option<(Vector3<f64>, Vec<Vector2<f64>>)> {
    let mut s = bl.c;
    for k in 0..3 {
        s[(k, k)] += lambda * bl.c[(k, k)].max(f64::MIN_POSITIVE);
    }
    let mut rhs = bl.gs;
    let mut a_inv = Vec::with_capacity(bl.a.len());
    for i in 0..bl.a.len() {
        let mut a = bl.a[i];
        for k in 0..2 {
            a[(k, k)] += lambda * bl.a[i][(k, k)].max(f64::MIN_POSITIVE);
        }
        let inv = a.try_inverse()?;
        s -= bl.b[i] * inv * bl.b[i].transpose();
        rhs -= bl.b[i] * inv * bl.gi[i];
        a_inv.push(inv);
    }
    let ds = s.cholesky()?.solve(&rhs);
    let dl = (0..bl.a.len())
        .map(|i| a_inv[i] * (bl.gi[i] - bl.b[i].transpose() * ds))
        .collect();
    Some((ds, dl))
}

fn fisher(bl: &Blocks) -> DMatrix<f64> {
    let m = bl.a.len();
    let n = 3 + 2 * m;
    let mut f = DMatrix::zeros(n, n);
    f.view_mut((0, 0), (3, 3)).copy_from(&bl.c);
    for i in 0..m {
        let o = 3 + 2 * i;
        f.view_mut((o, o), (2, 2)).copy_from(&bl.a[i]);
        f.view_mut((0, o), (3, 2)).copy_from(&bl.b[i]);
        f.view_mut((o, 0), (2, 3)).copy_from(&bl.b[i].transpose());
    }
    f
}

/// The Bouc-Wen conditions of (2a) (`beta + gamma > 0`, `beta >= gamma`) and the mu bracket.
fn admissible(p: &Params, opts: &Options) -> bool {
    p.mu > opts.mu_lo.max(1.0) + MU_MARGIN
        && p.mu <= opts.mu_hi
        && p.beta + p.gamma > 0.0
        && p.beta >= p.gamma
}

/// Projects a trial point onto the closed constraints it crossed, so that the fit can slide along
/// `beta = gamma` or a bracket end instead of stalling at the first contact: `beta < gamma` becomes
/// `beta = gamma = (beta + gamma) / 2` (the nearest point of the plane, same `beta + gamma`), and `mu`
/// is clipped into the bracket. `beta + gamma <= 0` has no nearest admissible point and stays rejected.
fn project(p: &mut Params, opts: &Options) {
    if p.beta < p.gamma {
        let mid = 0.5 * (p.beta + p.gamma);
        p.beta = mid;
        p.gamma = mid;
    }
    let mu_min = opts.mu_lo.max(1.0) + 2.0 * MU_MARGIN;
    if p.mu.is_finite() {
        p.mu = p.mu.clamp(mu_min, opts.mu_hi.max(mu_min));
    }
}

fn validate(exps: &[Experiment], p: &Params, opts: &Options) -> Result<()> {
    if exps.is_empty() {
        return Err(CoreError::InsufficientData(
            "the refinement needs at least one experiment".into(),
        ));
    }
    if p.gains.len() != exps.len() || p.phases.len() != exps.len() {
        return Err(CoreError::InvalidParameter(format!(
            "{} experiments but {} gains and {} phases",
            exps.len(),
            p.gains.len(),
            p.phases.len()
        )));
    }
    for (i, e) in exps.iter().enumerate() {
        all_finite(&format!("ybar[{i}]"), e.ybar)?;
        finite("amplitude", e.amplitude)?;
        finite("weight", e.weight)?;
        if e.weight <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "experiment {i}: weight {} must be > 0 (N / noise variance)",
                e.weight
            )));
        }
    }
    all_finite("gains", &p.gains)?;
    all_finite("phases", &p.phases)?;
    if opts.max_iter == 0 || opts.substeps == 0 {
        return Err(CoreError::InvalidParameter(
            "max_iter and substeps must be >= 1".into(),
        ));
    }
    if !admissible(p, opts) {
        return Err(CoreError::InvalidParameter(format!(
            "the starting point (beta = {}, gamma = {}, mu = {}) must satisfy beta >= |gamma|, \
             beta + gamma > 0 and {} < mu <= {}",
            p.beta,
            p.gamma,
            p.mu,
            opts.mu_lo.max(1.0),
            opts.mu_hi
        )));
    }
    Ok(())
}

/// Levenberg-Marquardt from `start` (e.g. the profile-phase SLS estimates).
///
/// Every trial point must satisfy the Bouc-Wen conditions and the mu bracket (see `admissible`): a
/// step that crosses `beta = gamma` or a bracket end is projected back onto it (see `project`), one
/// that makes `beta + gamma <= 0` is rejected and the damping grows. So the fit stays admissible and
/// may end on a constraint.
///
/// Errors: an inadmissible start, the start is not a valid loop (see [`steady_loop`]), inconsistent
/// lengths, non-finite data, a non-positive weight.
pub fn refine(exps: &[Experiment], start: &Params, opts: &Options) -> Result<Fit> {
    validate(exps, start, opts)?;
    let mut p = start.clone();
    let mut ev = evaluate(exps, &p, opts.substeps)?;
    let mut bl = blocks(exps, &ev);
    let mut lambda = LAMBDA_START;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < opts.max_iter {
        iterations += 1;
        let Some((ds, dl)) = step(&bl, lambda) else {
            lambda *= LAMBDA_UP;
            if lambda > LAMBDA_MAX {
                converged = true;
                break;
            }
            continue;
        };
        let mut trial = p.clone();
        trial.beta += ds[0];
        trial.gamma += ds[1];
        trial.mu += ds[2];
        for (i, d) in dl.iter().enumerate() {
            trial.gains[i] += d[0];
            trial.phases[i] += d[1];
        }
        let small = {
            let mut pairs = vec![(ds[0], p.beta), (ds[1], p.gamma), (ds[2], p.mu)];
            for (i, d) in dl.iter().enumerate() {
                pairs.push((d[0], p.gains[i]));
                pairs.push((d[1], p.phases[i]));
            }
            pairs
                .iter()
                .all(|(d, v)| d.abs() <= opts.xtol * (v.abs() + opts.xtol))
        };
        project(&mut trial, opts);
        let admissible = admissible(&trial, opts);
        let trial_ev = if admissible {
            evaluate(exps, &trial, opts.substeps).ok()
        } else {
            None
        };
        match trial_ev {
            Some(tev) if tev.cost <= ev.cost => {
                let decrease = (ev.cost - tev.cost) / ev.cost.max(f64::MIN_POSITIVE);
                p = trial;
                ev = tev;
                bl = blocks(exps, &ev);
                lambda = (lambda * LAMBDA_DOWN).max(1e-15);
                if decrease < opts.ftol || small {
                    converged = true;
                    break;
                }
            }
            _ => {
                if small {
                    converged = true;
                    break;
                }
                lambda *= LAMBDA_UP;
                if lambda > LAMBDA_MAX {
                    converged = true;
                    break;
                }
            }
        }
    }
    Ok(Fit {
        fisher: fisher(&bl),
        loops: ev.loops.into_iter().map(|l| l.w).collect(),
        cost: ev.cost,
        params: p,
        iterations,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(a: f64, beta: f64, gamma: f64, mu: f64, phi: f64, p: usize) -> Vec<f64> {
        steady_loop(a, beta, gamma, mu, phi, p, 8).unwrap().w
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

//! The augmented model (`docs/design.md` 9.1, 9.3): one experiment's output with the physical
//! terms and its Jacobian, and the joint Levenberg-Marquardt over every experiment. The terms'
//! vocabulary (names, ranges) is [`crate::terms`]; the NumPy oracle is `reference/augmented.py`.
//!
//! Per sine experiment, on the averaged period's grid `theta_j = 2 pi j / P`:
//! `y_j = y0 + H_tau[w_j + k u_j + c udot_j + m uddot_j + f tanh(udot_j / (eps U omega))]_j`
//! with the measured input `u_j = U cos(theta_j + psi)` and the hysteresis `w` of the latent
//! `x_j = A cos(theta_j - phi)`, `A = U g`. The mechanical terms act on u, in parallel with the
//! Wiener system, as the spring and dashpot of Spencer's phenomenological MR-damper model act on
//! the piston displacement (Spencer, Dyke, Sain & Carlson, J. Eng. Mech. 123(3), 1997). `H_tau`
//! is the periodic steady state of the first-order lag `tau ydot + y = F`, applied on the DFT of
//! the period. The hysteresis is the plain steady loop of 7.2 ([`crate::steady::steady_loop`])
//! unless asymmetry or play is active, then the loop along the input path of 9.2
//! ([`crate::path_loop::path_loop`]).
//!
//! The Jacobian has the shared columns `[beta, gamma, mu, q_1 .. q_T]` (the active terms'
//! parameters in the order given) and the experiment's own columns `[g, phi]`; `H_tau` is linear,
//! so every column but `tau`'s is the filtered derivative of `F`, and `tau`'s is
//! `dY_k/dtau = -i k omega F_k / (1 + i k omega tau)^2`.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::cell::RefCell;

use crate::dahl::{dahl_loop, DahlLoop};
use crate::error::{all_finite, finite, CoreError, Result};
use crate::path_loop::{
    path_loop, path_loop_distorted, path_loop_pinched, Waveform, N_PD, PD_AMPLITUDE, PD_BETA,
    PD_DELTA, PD_DISTORT, PD_GAMMA, PD_MU, PD_PHI, PD_PINCH, PD_PLAY,
};
use crate::refine::{
    check_joint_start, check_start_point, hysteresis_admissible, hysteresis_constraints,
    levenberg_marquardt, project_hysteresis, Constraint, JointModel, ModelEval, Options,
    StopReason,
};
use crate::series_loop::{
    series_loop, SD_AMPLITUDE, SD_BETA, SD_DELTA, SD_GAMMA, SD_MU, SD_PHI, SD_R,
};
use crate::steady::{steady_loop, D_AMPLITUDE, D_BETA, D_GAMMA, D_MU, D_PHI};
use crate::terms::{
    check_asymmetry, Place, TermKind, Terms, COULOMB_SMOOTHING, N_HYSTERESIS, PINCHING_MAX,
};

/// Own parameters per experiment: `g, phi`.
pub const N_OWN: usize = 2;

/// The sine excitation of one experiment and its averaged period's grid.
#[derive(Debug, Clone, Copy)]
pub struct Excitation {
    /// Samples per period P of the averaged period.
    pub samples: usize,
    /// Input amplitude U ([u], non-zero).
    pub amplitude: f64,
    /// Angular frequency omega (rad/s, > 0).
    pub frequency: f64,
    /// Grid phase psi (rad): `u_j = U cos(2 pi j/P + psi)`.
    pub grid_phase: f64,
}

impl Excitation {
    /// Checks finiteness, `U != 0`, `omega > 0`.
    pub fn validate(&self) -> Result<()> {
        finite("amplitude", self.amplitude)?;
        finite("frequency", self.frequency)?;
        finite("grid_phase", self.grid_phase)?;
        if self.amplitude == 0.0 {
            return Err(CoreError::ZeroAmplitude(
                "the input amplitude U is 0: nothing excites the plant".into(),
            ));
        }
        if self.frequency <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "frequency = {} rad/s must be > 0",
                self.frequency
            )));
        }
        Ok(())
    }
}

/// The model output of one experiment and its Jacobian.
#[derive(Debug, Clone)]
pub struct AugOutput {
    /// `y_j`, j = 0..P ([y]).
    pub y: Vec<f64>,
    /// `dy_j / d[beta, gamma, mu, q_1 .. q_T]`, row-major (P, 3 + T).
    pub jac_shared: Vec<f64>,
    /// `dy_j / d[g, phi]`, one row per sample.
    pub jac_own: Vec<[f64; 2]>,
}

/// Checks the shared vector against the terms and the admissible ranges of 9.1 that do not
/// depend on the experiment (`tau >= 0`, `b >= 0`, `|delta| < beta + gamma`).
pub fn check_shared(terms: &Terms, shared: &[f64]) -> Result<()> {
    if shared.len() != terms.n_shared() {
        return Err(CoreError::InvalidParameter(format!(
            "the shared parameters hold {} values but [beta, gamma, mu] and {} terms need {}",
            shared.len(),
            terms.len(),
            terms.n_shared()
        )));
    }
    all_finite("shared parameters", shared)?;
    for (&kind, &value) in terms.kinds().iter().zip(&shared[N_HYSTERESIS..]) {
        kind.check_value(value)?;
        if kind == TermKind::Asymmetry {
            check_asymmetry(value, shared[0], shared[1])?;
        }
    }
    Ok(())
}

/// The hysteresis `w` and its columns `d/d(beta, gamma, mu, A, phi, delta, b)` (the last two 0
/// for the plain loop).
#[allow(clippy::too_many_arguments)]
fn hysteresis(
    terms: &Terms,
    shared: &[f64],
    amplitude: f64,
    phi: f64,
    waveform: &[f64],
    p: usize,
    substeps: usize,
) -> Result<(Vec<f64>, Vec<[f64; N_PD]>)> {
    let (beta, gamma, mu) = (shared[0], shared[1], shared[2]);
    if terms.needs_path_loop() {
        let delta = terms.value(shared, TermKind::Asymmetry);
        let b = terms.value(shared, TermKind::Play);
        let wf = terms.column(TermKind::Distortion).map(|c| Waveform {
            lambda: shared[c],
            harmonics: waveform,
        });
        let l = match (terms.column(TermKind::Pinching), &wf) {
            // Pinching: Foliente's factor on h(w, s) (rust/path_loop.rs).
            (Some(c), wf) => path_loop_pinched(
                amplitude,
                beta,
                gamma,
                mu,
                delta,
                b,
                phi,
                shared[c],
                wf.as_ref(),
                p,
                substeps,
            )?,
            (None, Some(wf)) => {
                path_loop_distorted(amplitude, beta, gamma, mu, delta, b, phi, wf, p, substeps)?
            }
            (None, None) => path_loop(amplitude, beta, gamma, mu, delta, b, phi, p, substeps)?,
        };
        Ok((l.w, l.jac))
    } else {
        let l = steady_loop(amplitude, beta, gamma, mu, phi, p, substeps)?;
        let jac = l
            .jac
            .iter()
            .map(|r| {
                let mut row = [0.0; N_PD];
                row[PD_BETA] = r[D_BETA];
                row[PD_GAMMA] = r[D_GAMMA];
                row[PD_MU] = r[D_MU];
                row[PD_AMPLITUDE] = r[D_AMPLITUDE];
                row[PD_PHI] = r[D_PHI];
                row
            })
            .collect();
        Ok((l.w, jac))
    }
}

/// `w`, its rows of columns `PD_*`, and `d w / d rho` per sample.
type SeriesHysteresis = (Vec<f64>, Vec<[f64; N_PD]>, Vec<f64>);

/// The hysteresis behind Spencer's series dashpot (`rust/series_loop.rs`) with its columns
/// `d/d(beta, gamma, mu, A, phi, delta)` as [`hysteresis`]'s rows and `d/drho` per sample
/// (`r = rho / omega`). Asymmetry rides along; play, pinching and a distorted waveform do not
/// (a named error).
#[allow(clippy::too_many_arguments)]
fn series_hysteresis(
    terms: &Terms,
    shared: &[f64],
    amplitude: f64,
    phi: f64,
    omega: f64,
    rho: f64,
    p: usize,
    substeps: usize,
) -> Result<SeriesHysteresis> {
    for other in [TermKind::Play, TermKind::Pinching, TermKind::Distortion] {
        if terms.column(other).is_some() {
            return Err(CoreError::InvalidParameter(format!(
                "term {:?} with {:?}: the series dashpot's steady loop carries the asymmetry only",
                TermKind::SeriesDashpot.name(),
                other.name()
            )));
        }
    }
    let delta = terms.value(shared, TermKind::Asymmetry);
    let (beta, gamma, mu) = (shared[0], shared[1], shared[2]);
    let l = series_loop(
        amplitude,
        beta,
        gamma,
        mu,
        delta,
        phi,
        rho / omega,
        p,
        substeps,
    )?;
    let jac = l
        .jac
        .iter()
        .map(|r| {
            let mut row = [0.0; N_PD];
            row[PD_BETA] = r[SD_BETA];
            row[PD_GAMMA] = r[SD_GAMMA];
            row[PD_MU] = r[SD_MU];
            row[PD_AMPLITUDE] = r[SD_AMPLITUDE];
            row[PD_PHI] = r[SD_PHI];
            row[PD_DELTA] = r[SD_DELTA];
            row
        })
        .collect();
    let d_rho = l.jac.iter().map(|r| r[SD_R] / omega).collect();
    Ok((l.w, jac, d_rho))
}

/// The lag filter of bin `n` of a P-point DFT at `tau`, and its derivative in `tau`.
///
/// Harmonic `k = n` for `n < P/2`, `n - P` above; the Nyquist bin of an even P takes the real
/// `Re 1/(1 + i (P/2) omega tau)` so that the output stays real.
fn lag_bin(n: usize, p: usize, omega: f64, tau: f64) -> (Complex<f64>, Complex<f64>) {
    let one = Complex::new(1.0, 0.0);
    if 2 * n == p {
        let a = (p / 2) as f64 * omega;
        let d = 1.0 + a * a * tau * tau;
        return (
            Complex::new(1.0 / d, 0.0),
            Complex::new(-2.0 * a * a * tau / (d * d), 0.0),
        );
    }
    let k = if 2 * n < p {
        n as f64
    } else {
        n as f64 - p as f64
    };
    let iw = Complex::new(0.0, k * omega);
    let den = one + iw * tau;
    let h = one / den;
    (h, -iw * h * h)
}

thread_local! {
    /// The lag filter's FFT plans, kept per thread by size (issue 18 item 4): planned afresh on
    /// every call, a prime size (the MR damper's P = 401, 37: Bluestein) cost more than the
    /// transforms. A size always gets the same algorithm, so the outputs are the same bit for bit.
    static LAG_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// Applies the lag (`derivative == false`) or its tau-derivative to real columns in place, two
/// columns per complex FFT (the filter is Hermitian, so it maps the real and imaginary parts
/// separately).
fn apply_lag(cols: &mut [&mut [f64]], omega: f64, tau: f64, derivative: bool) {
    let Some(first) = cols.first() else {
        return;
    };
    let p = first.len();
    let (fwd, inv) = LAG_PLANNER.with(|planner| {
        let mut planner = planner.borrow_mut();
        (planner.plan_fft_forward(p), planner.plan_fft_inverse(p))
    });
    let filt: Vec<Complex<f64>> = (0..p)
        .map(|n| {
            let (h, dh) = lag_bin(n, p, omega, tau);
            if derivative {
                dh
            } else {
                h
            }
        })
        .collect();
    let scale = 1.0 / p as f64;
    let mut buf = vec![Complex::new(0.0, 0.0); p];
    for pair in cols.chunks_mut(2) {
        for (j, z) in buf.iter_mut().enumerate() {
            let im = if pair.len() > 1 { pair[1][j] } else { 0.0 };
            *z = Complex::new(pair[0][j], im);
        }
        fwd.process(&mut buf);
        for (z, h) in buf.iter_mut().zip(&filt) {
            *z *= h * scale;
        }
        inv.process(&mut buf);
        for (j, z) in buf.iter().enumerate() {
            pair[0][j] = z.re;
            if pair.len() > 1 {
                pair[1][j] = z.im;
            }
        }
    }
}

/// The augmented model's output of one experiment (design.md 9.1) and its Jacobian.
///
/// `shared = [beta, gamma, mu, q_1 .. q_T]` in the order of `terms`; `gain` is the signed g of
/// `A = U g` ([x]/[u]), `phase` the phi of `x_j = A cos(theta_j - phi)` (rad, grid frame);
/// `substeps` RK4 steps per lattice interval (plain loop) or per segment (path loop).
///
/// Errors: inconsistent or non-finite parameters, a term outside its admissible range
/// (see [`check_shared`], and `b < |A|`), and every error of the loop solvers.
pub fn augmented_output(
    exc: &Excitation,
    terms: &Terms,
    shared: &[f64],
    gain: f64,
    phase: f64,
    substeps: usize,
) -> Result<AugOutput> {
    augmented_output_with(exc, &[], terms, shared, gain, phase, substeps)
}

/// [`augmented_output`] of an experiment whose measured input waveform (design.md 9.5) is
/// `waveform = [Re c_2, Im c_2, Re c_3, ...]` (relative to the fundamental; empty: a pure sine),
/// used by the `distortion` term. The mechanical terms still see the fundamental of u.
pub fn augmented_output_with(
    exc: &Excitation,
    waveform: &[f64],
    terms: &Terms,
    shared: &[f64],
    gain: f64,
    phase: f64,
    substeps: usize,
) -> Result<AugOutput> {
    exc.validate()?;
    check_shared(terms, shared)?;
    finite("gain", gain)?;
    finite("phase", phase)?;
    let p = exc.samples;
    let ns = terms.n_shared();
    let (u_amp, omega) = (exc.amplitude, exc.frequency);
    let (w, hjac, d_series) = match terms.column(TermKind::SeriesDashpot) {
        Some(c) => series_hysteresis(
            terms,
            shared,
            u_amp * gain,
            phase,
            omega,
            shared[c],
            p,
            substeps,
        )?,
        None => {
            let (w, hjac) = hysteresis(terms, shared, u_amp * gain, phase, waveform, p, substeps)?;
            (w, hjac, Vec::new())
        }
    };
    // Column-major work space: F, then the shared columns, then g and phi.
    let ncol = 1 + ns + N_OWN;
    let mut cols = vec![vec![0.0; p]; ncol];
    let step = 2.0 * std::f64::consts::PI / p as f64;
    let mut lag_col = None;
    let mut offset_col = None;
    let dahl = dahl_loops(terms, shared, exc, gain, phase)?;
    for j in 0..p {
        let th = step * j as f64 + exc.grid_phase;
        let (s, c) = th.sin_cos();
        let u = u_amp * c;
        let udot = -u_amp * omega * s;
        let uddot = -u_amp * omega * omega * c;
        // The peak input velocity |U| omega: the smoothed sign follows sgn(udot) for either sign
        // of U.
        let fric = (udot / (COULOMB_SMOOTHING * u_amp.abs() * omega)).tanh();
        let h = &hjac[j];
        let mut f = w[j];
        // The on-x terms' share of the own columns d/dg and d/dphi.
        let (mut dg, mut dphi) = (0.0, 0.0);
        cols[1][j] = h[PD_BETA];
        cols[2][j] = h[PD_GAMMA];
        cols[3][j] = h[PD_MU];
        for (t, &kind) in terms.kinds().iter().enumerate() {
            let q = shared[N_HYSTERESIS + t];
            let col = &mut cols[1 + N_HYSTERESIS + t];
            if let Some((l, on_x)) = dahl_of(&dahl, kind, terms.place(t)) {
                // Dahl friction (rust/dahl.rs): the level's column carries F itself; the
                // on-x loop's phase follows (g, phi).
                if kind == TermKind::Dahl {
                    f += l.f[j];
                    col[j] = l.d_fc[j];
                    if on_x {
                        dg += u_amp * l.d_amplitude[j];
                        dphi -= l.d_phase[j];
                    }
                } else {
                    col[j] = l.d_sigma[j];
                }
                continue;
            }
            if terms.place(t) == Place::X {
                let (v, dv_da, dv_dphi) =
                    on_x_regressor(kind, u_amp * gain, omega, step * j as f64 - phase);
                f += q * v;
                col[j] = v;
                dg += q * u_amp * dv_da;
                dphi += q * dv_dphi;
                continue;
            }
            match kind {
                TermKind::Offset => offset_col = Some(1 + N_HYSTERESIS + t),
                TermKind::Stiffness => {
                    f += q * u;
                    col[j] = u;
                }
                TermKind::Viscous => {
                    f += q * udot;
                    col[j] = udot;
                }
                TermKind::Inertia => {
                    f += q * uddot;
                    col[j] = uddot;
                }
                TermKind::Coulomb => {
                    f += q * fric;
                    col[j] = fric;
                }
                TermKind::SensorLag => lag_col = Some(1 + N_HYSTERESIS + t),
                TermKind::Asymmetry => col[j] = h[PD_DELTA],
                TermKind::Play => col[j] = h[PD_PLAY],
                TermKind::Distortion => col[j] = h[PD_DISTORT],
                // Refused by `Terms::parse`: the steady loop has no form for it.
                TermKind::Degradation => {}
                TermKind::Pinching => col[j] = h[PD_PINCH],
                // Refused by `Terms::parse` as well (no steady loop).
                TermKind::StiffnessDegradation => {}
                TermKind::SeriesDashpot => col[j] = d_series[j],
                // Handled above (`dahl_of`).
                TermKind::Dahl | TermKind::DahlSigma => {}
            }
        }
        cols[0][j] = f;
        cols[1 + ns][j] = u_amp * h[PD_AMPLITUDE] + dg;
        cols[2 + ns][j] = h[PD_PHI] + dphi;
    }
    lag_and_offset(&mut cols, shared, omega, lag_col, offset_col);
    let mut jac_shared = vec![0.0; p * ns];
    for (c, col) in cols[1..=ns].iter().enumerate() {
        for (j, v) in col.iter().enumerate() {
            jac_shared[j * ns + c] = *v;
        }
    }
    let jac_own = (0..p).map(|j| [cols[1 + ns][j], cols[2 + ns][j]]).collect();
    let y = std::mem::take(&mut cols[0]);
    all_finite("model output", &y)?;
    Ok(AugOutput {
        y,
        jac_shared,
        jac_own,
    })
}

/// The steady Dahl loops of the active Dahl friction, `(on u, on x)` (rust/dahl.rs): on u driven
/// by `u_j = U cos(theta_j + psi)`, on x by `x_j = U g cos(theta_j - phi)`.
fn dahl_loops(
    terms: &Terms,
    shared: &[f64],
    exc: &Excitation,
    gain: f64,
    phase: f64,
) -> Result<[Option<DahlLoop>; 2]> {
    let at = |place: Place, a: f64, psi0: f64| -> Result<Option<DahlLoop>> {
        match (
            terms.column_at(TermKind::Dahl, place),
            terms.column_at(TermKind::DahlSigma, place),
        ) {
            (Some(cf), Some(cs)) => Ok(Some(dahl_loop(
                a,
                psi0,
                shared[cf],
                shared[cs],
                exc.samples,
            )?)),
            _ => Ok(None),
        }
    };
    Ok([
        at(Place::Usual, exc.amplitude, exc.grid_phase)?,
        at(Place::X, exc.amplitude * gain, -phase)?,
    ])
}

/// The Dahl loop of a Dahl parameter's term at `place`, and whether it acts on x; `None` for
/// the other terms.
fn dahl_of(
    dahl: &[Option<DahlLoop>; 2],
    kind: TermKind,
    place: Place,
) -> Option<(&DahlLoop, bool)> {
    if !matches!(kind, TermKind::Dahl | TermKind::DahlSigma) {
        return None;
    }
    let on_x = place == Place::X;
    dahl[usize::from(on_x)].as_ref().map(|l| (l, on_x))
}

/// The regressor of a mechanical term acting across the hysteretic element, on its input
/// `x = a cos(z)`, `z = theta_j - phi` (design.md 9.1, place x), with its derivatives in `a` and
/// `phi`: `k x`, `c xdot`, `m xddot`, `f tanh(xdot / (eps |a| omega))`. The distortion term's
/// harmonics are not seen here (as the on-u terms see the fundamental of u).
fn on_x_regressor(kind: TermKind, a: f64, omega: f64, z: f64) -> (f64, f64, f64) {
    let (s, c) = z.sin_cos();
    match kind {
        TermKind::Stiffness => (a * c, c, a * s),
        TermKind::Viscous => (-a * omega * s, -omega * s, a * omega * c),
        TermKind::Inertia => (
            -a * omega * omega * c,
            -omega * omega * c,
            -a * omega * omega * s,
        ),
        TermKind::Coulomb => {
            // xdot / (eps |a| omega) = -sgn(a) sin z / eps: independent of |a|.
            let sg = a.signum();
            let v = (-sg * s / COULOMB_SMOOTHING).tanh();
            (v, 0.0, (1.0 - v * v) * sg * c / COULOMB_SMOOTHING)
        }
        // Refused by `Terms::parse` (`TermKind::acts_at`).
        _ => (0.0, 0.0, 0.0),
    }
}

/// The output stage of [`augmented_output_with`] on the work space `cols` (F, then the shared
/// columns, then g and phi, each of P samples): the sensor lag filters every column but its own
/// and the offset's, its own column becomes `dY/dtau`; the offset is added after the lag, its
/// column is 1. `lag_col`, `offset_col` index `cols` (the parameter is `shared[col - 1]`).
fn lag_and_offset(
    cols: &mut [Vec<f64>],
    shared: &[f64],
    omega: f64,
    lag_col: Option<usize>,
    offset_col: Option<usize>,
) {
    if let Some(lc) = lag_col {
        let tau = shared[lc - 1];
        let mut dtau = cols[0].clone();
        apply_lag(&mut [&mut dtau[..]], omega, tau, true);
        let mut filtered: Vec<&mut [f64]> = cols
            .iter_mut()
            .enumerate()
            .filter(|&(c, _)| Some(c) != lag_col && Some(c) != offset_col)
            .map(|(_, v)| &mut v[..])
            .collect();
        apply_lag(&mut filtered, omega, tau, false);
        cols[lc] = dtau;
    }
    if let Some(oc) = offset_col {
        let y0 = shared[oc - 1];
        cols[0].iter_mut().for_each(|v| *v += y0);
        cols[oc].iter_mut().for_each(|v| *v = 1.0);
    }
}

/// One experiment of the augmented refinement: its averaged period (with its DC), excitation and
/// weight.
#[derive(Debug, Clone, Copy)]
pub struct AugExperiment<'a> {
    /// Averaged output over one period, length P, on `t_j = j T / P` ([y], DC kept).
    pub ybar: &'a [f64],
    /// Input amplitude U ([u], non-zero).
    pub amplitude: f64,
    /// Angular frequency omega (rad/s).
    pub frequency: f64,
    /// Grid phase psi (rad) of the input on the averaged period's grid.
    pub grid_phase: f64,
    /// Weight of each squared residual, `N / sigma^2`.
    pub weight: f64,
    /// The measured input's waveform beyond its fundamental, `[Re c_2, Im c_2, ...]` (design.md
    /// 9.5; empty for a pure sine), used by the `distortion` term.
    pub waveform: &'a [f64],
    /// RK4 steps per lattice interval / path segment for this experiment; `None`: the refinement's
    /// [`Options::substeps`]. A coarse grid needs more steps per sample than a fine one for the
    /// same step in phase, so one count for all would make every fine grid pay for the coarsest.
    pub substeps: Option<usize>,
}

impl AugExperiment<'_> {
    fn excitation(&self) -> Excitation {
        Excitation {
            samples: self.ybar.len(),
            amplitude: self.amplitude,
            frequency: self.frequency,
            grid_phase: self.grid_phase,
        }
    }
}

/// Outcome of [`augmented_refine`].
#[derive(Debug, Clone)]
pub struct AugFit {
    /// `[beta, gamma, mu, q_1 .. q_T]` at the minimiser.
    pub shared: Vec<f64>,
    /// Signed gains `g_i`.
    pub gains: Vec<f64>,
    /// Phases `phi_i` (rad, grid frame).
    pub phases: Vec<f64>,
    /// Weighted residual sum of squares.
    pub cost: f64,
    /// Accepted plus rejected LM iterations.
    pub iterations: usize,
    /// Whether a stopping rule other than the iteration cap ended the search.
    pub converged: bool,
    /// The stopping rule that ended the search.
    pub stop: StopReason,
    /// The constraints the minimiser sits on and that hold it there (e.g. `"beta=gamma"`,
    /// `"mu=lower"`, `"sensor_lag=0"`, `"play=upper"`).
    pub active: Vec<String>,
    /// `J^T W J`, order `[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]`.
    pub fisher: nalgebra::DMatrix<f64>,
    /// Model outputs `y_i` at the minimiser.
    pub outputs: Vec<Vec<f64>>,
}

/// Largest play as a fraction of the smallest `|A_i|`: beyond it some experiment's hysteresis
/// barely moves and its loop is ill-determined.
pub const PLAY_MAX_FRACTION: f64 = 0.95;

struct AugModel<'a> {
    exps: &'a [AugExperiment<'a>],
    terms: &'a Terms,
    opts: &'a Options,
}

impl AugModel<'_> {
    /// The columns of Dahl friction's two parameters (>= 0) at every place, with their names.
    fn dahl_columns(&self) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        for place in [Place::Usual, Place::X] {
            for kind in [TermKind::Dahl, TermKind::DahlSigma] {
                if let Some(c) = self.terms.column_at(kind, place) {
                    let name = if place == Place::Usual {
                        kind.name().to_string()
                    } else {
                        format!("{}@{}", kind.name(), place.tag())
                    };
                    out.push((c, name));
                }
            }
        }
        out
    }

    fn play_max(&self, own: &[[f64; 2]]) -> f64 {
        PLAY_MAX_FRACTION
            * self
                .exps
                .iter()
                .zip(own)
                .map(|(e, o)| (e.amplitude * o[0]).abs())
                .fold(f64::INFINITY, f64::min)
    }
}

impl JointModel for AugModel<'_> {
    fn n_shared(&self) -> usize {
        self.terms.n_shared()
    }

    fn n_experiments(&self) -> usize {
        self.exps.len()
    }

    fn data(&self, i: usize) -> (&[f64], f64) {
        (self.exps[i].ybar, self.exps[i].weight)
    }

    fn evaluate(&self, i: usize, shared: &[f64], own: [f64; 2]) -> Result<ModelEval> {
        let out = augmented_output_with(
            &self.exps[i].excitation(),
            self.exps[i].waveform,
            self.terms,
            shared,
            own[0],
            own[1],
            self.exps[i].substeps.unwrap_or(self.opts.substeps),
        )?;
        Ok(ModelEval {
            y: out.y,
            jac_shared: out.jac_shared,
            jac_own: out.jac_own,
        })
    }

    fn constraints(&self, own: &[[f64; 2]]) -> Vec<Constraint> {
        let mut cons = hysteresis_constraints(self.opts.mu_lo, self.opts.mu_hi);
        // The terms' closed ranges, as `project` clips them: `name=0` and `name=upper`.
        let mut bound = |kind: TermKind, upper: Option<f64>| {
            if let Some(c) = self.terms.column(kind) {
                cons.push(Constraint {
                    name: format!("{}=0", kind.name()),
                    normal: vec![(c, 1.0)],
                    bound: 0.0,
                });
                if let Some(hi) = upper {
                    cons.push(Constraint {
                        name: format!("{}=upper", kind.name()),
                        normal: vec![(c, -1.0)],
                        bound: -hi,
                    });
                }
            }
        };
        bound(TermKind::SensorLag, None);
        bound(TermKind::Play, Some(self.play_max(own)));
        bound(TermKind::Pinching, Some(PINCHING_MAX));
        bound(TermKind::SeriesDashpot, None);
        for (c, name) in self.dahl_columns() {
            cons.push(Constraint {
                name: format!("{name}=0"),
                normal: vec![(c, 1.0)],
                bound: 0.0,
            });
        }
        cons
    }

    fn project(&self, shared: &mut [f64], own: &[[f64; 2]]) {
        project_hysteresis(shared, self.opts.mu_lo, self.opts.mu_hi);
        if let Some(c) = self.terms.column(TermKind::SensorLag) {
            shared[c] = shared[c].max(0.0);
        }
        if let Some(c) = self.terms.column(TermKind::Play) {
            shared[c] = shared[c].min(self.play_max(own)).max(0.0);
        }
        if let Some(c) = self.terms.column(TermKind::Pinching) {
            shared[c] = shared[c].clamp(0.0, PINCHING_MAX);
        }
        if let Some(c) = self.terms.column(TermKind::SeriesDashpot) {
            shared[c] = shared[c].max(0.0);
        }
        for (c, _) in self.dahl_columns() {
            shared[c] = shared[c].max(0.0);
        }
    }

    fn admissible(&self, shared: &[f64], own: &[[f64; 2]]) -> bool {
        let delta_ok = self
            .terms
            .column(TermKind::Asymmetry)
            .is_none_or(|c| shared[c].abs() < shared[0] + shared[1]);
        let tau_ok = self
            .terms
            .column(TermKind::SensorLag)
            .is_none_or(|c| shared[c] >= 0.0);
        let play_ok = self
            .terms
            .column(TermKind::Play)
            .is_none_or(|c| shared[c] >= 0.0 && shared[c] <= self.play_max(own));
        let pinch_ok = self
            .terms
            .column(TermKind::Pinching)
            .is_none_or(|c| (0.0..=PINCHING_MAX).contains(&shared[c]));
        let series_ok = self
            .terms
            .column(TermKind::SeriesDashpot)
            .is_none_or(|c| shared[c] >= 0.0);
        let dahl_ok = self.dahl_columns().iter().all(|&(c, _)| shared[c] >= 0.0);
        hysteresis_admissible(shared, self.opts.mu_lo, self.opts.mu_hi)
            && dahl_ok
            && series_ok
            && pinch_ok
            && delta_ok
            && tau_ok
            && play_ok
    }
}

fn validate_refine(
    exps: &[AugExperiment],
    terms: &Terms,
    shared: &[f64],
    gains: &[f64],
    phases: &[f64],
    opts: &Options,
) -> Result<()> {
    let model = AugModel { exps, terms, opts };
    let excitation = |i: usize| exps[i].excitation().validate();
    check_joint_start(&model, excitation, (gains, phases), opts)?;
    if !opts.mu_lo.is_finite()
        || opts.mu_lo < 1.0
        || opts.mu_hi.is_nan()
        || opts.mu_hi <= opts.mu_lo
    {
        return Err(CoreError::InvalidParameter(format!(
            "the mu bracket ({}, {}] must have a finite lower end >= 1 below its upper end",
            opts.mu_lo, opts.mu_hi
        )));
    }
    check_shared(terms, shared)?;
    // mu_lo >= 1 here (the bracket is checked above): the message names the bracket as given.
    check_start_point(shared, opts)?;
    let b = terms.value(shared, TermKind::Play);
    let own: Vec<[f64; 2]> = gains.iter().zip(phases).map(|(&g, &p)| [g, p]).collect();
    if b > model.play_max(&own) {
        return Err(CoreError::InvalidParameter(format!(
            "the starting play b = {b} must be below {PLAY_MAX_FRACTION} min |U_i g_i| = {}",
            model.play_max(&own)
        )));
    }
    Ok(())
}

/// Joint Levenberg-Marquardt of the augmented model over every experiment (design.md 9.3).
///
/// `shared0 = [beta, gamma, mu, q_1 .. q_T]` in the order of `terms`; `gains0`, `phases0` one per
/// experiment. Same damping schedule, stopping rules and Schur solve as [`crate::refine::refine`]
/// ([`levenberg_marquardt`]); trial points are projected onto `beta = gamma` and the mu bracket,
/// `tau` and `b` are clipped at 0 and `b` below [`PLAY_MAX_FRACTION`] `min |A_i|`, and a trial
/// point with `|delta| >= beta + gamma` is rejected.
///
/// Errors: inconsistent lengths, non-finite or inadmissible start, bad mu bracket, non-positive
/// weight, and every error of [`augmented_output`] at the start.
pub fn augmented_refine(
    exps: &[AugExperiment],
    terms: &Terms,
    shared0: &[f64],
    gains0: &[f64],
    phases0: &[f64],
    opts: &Options,
) -> Result<AugFit> {
    validate_refine(exps, terms, shared0, gains0, phases0, opts)?;
    let model = AugModel { exps, terms, opts };
    let own: Vec<[f64; 2]> = gains0.iter().zip(phases0).map(|(&g, &p)| [g, p]).collect();
    let fit = levenberg_marquardt(&model, shared0, &own, opts)?;
    Ok(AugFit {
        gains: fit.own.iter().map(|o| o[0]).collect(),
        phases: fit.own.iter().map(|o| o[1]).collect(),
        shared: fit.shared,
        cost: fit.cost,
        iterations: fit.iterations,
        converged: fit.converged,
        stop: fit.stop,
        active: fit.active,
        fisher: fit.fisher,
        outputs: fit.outputs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use TermKind::*;

    /// The terms of `kinds`, through their code names as a caller gives them.
    fn terms_of(kinds: &[TermKind]) -> Terms {
        let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
        Terms::parse(&names).unwrap()
    }

    const EXC: Excitation = Excitation {
        samples: 64,
        amplitude: 1.7,
        frequency: 3.0,
        grid_phase: 0.4,
    };

    #[test]
    fn lag_filter_is_identity_at_zero_and_a_lag_of_the_fundamental() {
        // A pure fundamental through tau: amplitude 1/sqrt(1 + (omega tau)^2), lag atan(omega tau).
        let (p, omega, tau) = (32usize, 2.0, 0.3);
        let x: Vec<f64> = (0..p)
            .map(|j| (2.0 * std::f64::consts::PI * j as f64 / p as f64).cos())
            .collect();
        let mut y0 = x.clone();
        apply_lag(&mut [&mut y0[..]], omega, 0.0, false);
        let mut y = x.clone();
        apply_lag(&mut [&mut y[..]], omega, tau, false);
        let g = 1.0 / (1.0 + (omega * tau).powi(2)).sqrt();
        let lag = (omega * tau).atan();
        for j in 0..p {
            assert!((y0[j] - x[j]).abs() < 1e-14);
            let th = 2.0 * std::f64::consts::PI * j as f64 / p as f64;
            assert!((y[j] - g * (th - lag).cos()).abs() < 1e-14);
        }
    }

    /// Central differences of every shared and own column, with step `h` and relative tolerance.
    fn check_jacobian(terms: &[TermKind], shared: &[f64], exc: &Excitation, substeps: usize) {
        let terms = terms_of(terms);
        let (g, phi) = (0.9, 1.1);
        let out = augmented_output(exc, &terms, shared, g, phi, substeps).unwrap();
        let ns = shared.len();
        let h = 1e-6;
        let f = |s: &[f64], g: f64, phi: f64| {
            augmented_output(exc, &terms, s, g, phi, substeps)
                .unwrap()
                .y
        };
        for c in 0..ns + 2 {
            let (mut sp, mut sm) = (shared.to_vec(), shared.to_vec());
            let (mut gp, mut gm, mut pp, mut pm) = (g, g, phi, phi);
            match c {
                c if c < ns => {
                    sp[c] += h;
                    sm[c] -= h;
                }
                c if c == ns => {
                    gp += h;
                    gm -= h;
                }
                _ => {
                    pp += h;
                    pm -= h;
                }
            }
            let (yp, ym) = (f(&sp, gp, pp), f(&sm, gm, pm));
            let col: Vec<f64> = (0..exc.samples)
                .map(|j| {
                    if c < ns {
                        out.jac_shared[j * ns + c]
                    } else {
                        out.jac_own[j][c - ns]
                    }
                })
                .collect();
            let scale = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let err = (0..exc.samples)
                .map(|j| ((yp[j] - ym[j]) / (2.0 * h) - col[j]).abs())
                .fold(0.0, f64::max);
            // Central differences err by O(h^2) truncation plus O(eps / h) rounding, about 1e-9
            // relative. The phase column of the plain loop is its continuous rate (7.2), the
            // derivative of the discrete map only up to the RK4 error near w = 0 where |w|^mu is
            // not smooth: 1e-5 relative at 4 substeps, 1e-7 at 256 (measured), hence 256 here.
            assert!(
                err <= 1e-6 * scale.max(1e-3),
                "column {c}: {err} vs {scale}"
            );
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        check_jacobian(
            &[Offset, Stiffness, Viscous, Inertia, Coulomb, SensorLag],
            &[0.8, 0.2, 1.6, 0.3, 0.5, 0.05, 0.002, 0.2, 0.01],
            &EXC,
            256,
        );
        check_jacobian(
            &[SensorLag, Asymmetry, Play, Viscous],
            &[0.8, 0.2, 1.6, 0.02, 0.3, 0.2, 0.05],
            &Excitation { samples: 65, ..EXC },
            256,
        );
        check_jacobian(
            &[Pinching, Play, SensorLag],
            &[0.8, 0.2, 1.6, 0.4, 0.05, 0.02],
            &Excitation { samples: 64, ..EXC },
            256,
        );
    }

    #[test]
    fn series_dashpot_jacobian_matches_central_differences() {
        // Spencer's series dashpot (rust/series_loop.rs) with the asymmetry it carries and the
        // output terms around it; the series loop's columns are those of its discrete map.
        check_jacobian(
            &[SeriesDashpot, Asymmetry, SensorLag, Offset],
            &[0.8, 0.2, 1.6, 0.7, -0.1, 0.05, 0.3],
            &Excitation { samples: 48, ..EXC },
            8,
        );
        let both = terms_of(&[SeriesDashpot, Play]);
        let e = augmented_output(&EXC, &both, &[0.8, 0.2, 1.6, 0.5, 0.1], 0.9, 1.1, 4).unwrap_err();
        assert!(e.to_string().contains("asymmetry only"), "{e}");
    }

    #[test]
    fn dahl_jacobian_matches_central_differences() {
        // Dahl friction on u and on x (rust/dahl.rs) beside the lag and a spring on x.
        let on_x = |k: TermKind| format!("{}@{}", k.name(), Place::X.tag());
        let names = [
            on_x(Dahl),
            Dahl.name().to_string(),
            on_x(DahlSigma),
            SensorLag.name().to_string(),
            DahlSigma.name().to_string(),
            on_x(Stiffness),
        ];
        let terms = Terms::parse(&names).unwrap();
        let shared = [0.8, 0.2, 1.6, 0.1, 0.05, 0.3, 0.02, 0.4, 0.2];
        let (g, phi, h) = (-0.9, 1.1, 1e-6);
        let out = augmented_output(&EXC, &terms, &shared, g, phi, 256).unwrap();
        let f =
            |s: &[f64], g: f64, phi: f64| augmented_output(&EXC, &terms, s, g, phi, 256).unwrap().y;
        let ns = shared.len();
        for c in 0..ns + 2 {
            let (mut sp, mut sm) = (shared.to_vec(), shared.to_vec());
            let (mut gp, mut gm, mut pp, mut pm) = (g, g, phi, phi);
            if c < ns {
                sp[c] += h;
                sm[c] -= h;
            } else if c == ns {
                gp += h;
                gm -= h;
            } else {
                pp += h;
                pm -= h;
            }
            let (yp, ym) = (f(&sp, gp, pp), f(&sm, gm, pm));
            let col = |j: usize| {
                if c < ns {
                    out.jac_shared[j * ns + c]
                } else {
                    out.jac_own[j][c - ns]
                }
            };
            let scale = (0..EXC.samples).fold(0.0f64, |a, j| a.max(col(j).abs()));
            let err = (0..EXC.samples)
                .map(|j| ((yp[j] - ym[j]) / (2.0 * h) - col(j)).abs())
                .fold(0.0, f64::max);
            assert!(
                err <= 1e-6 * scale.max(1e-3),
                "column {c}: {err} vs {scale}"
            );
        }
    }

    #[test]
    fn on_x_terms_jacobian_matches_central_differences() {
        let on_x = |k: TermKind| format!("{}@{}", k.name(), Place::X.tag());
        let names = [
            on_x(Stiffness),
            on_x(Viscous),
            on_x(Inertia),
            on_x(Coulomb),
            Viscous.name().to_string(),
            SensorLag.name().to_string(),
        ];
        let terms = Terms::parse(&names).unwrap();
        let shared = [0.8, 0.2, 1.6, 0.3, 0.05, 0.002, 0.1, 0.02, 0.01];
        let (g, phi, h) = (0.9, 1.1, 1e-6);
        let out = augmented_output(&EXC, &terms, &shared, g, phi, 256).unwrap();
        let f =
            |s: &[f64], g: f64, phi: f64| augmented_output(&EXC, &terms, s, g, phi, 256).unwrap().y;
        let ns = shared.len();
        for c in 0..ns + 2 {
            let (mut sp, mut sm) = (shared.to_vec(), shared.to_vec());
            let (mut gp, mut gm, mut pp, mut pm) = (g, g, phi, phi);
            if c < ns {
                sp[c] += h;
                sm[c] -= h;
            } else if c == ns {
                gp += h;
                gm -= h;
            } else {
                pp += h;
                pm -= h;
            }
            let (yp, ym) = (f(&sp, gp, pp), f(&sm, gm, pm));
            let col = |j: usize| {
                if c < ns {
                    out.jac_shared[j * ns + c]
                } else {
                    out.jac_own[j][c - ns]
                }
            };
            let scale = (0..EXC.samples).fold(0.0f64, |a, j| a.max(col(j).abs()));
            let err = (0..EXC.samples)
                .map(|j| ((yp[j] - ym[j]) / (2.0 * h) - col(j)).abs())
                .fold(0.0, f64::max);
            assert!(
                err <= 1e-6 * scale.max(1e-3),
                "column {c}: {err} vs {scale}"
            );
        }
    }

    #[test]
    fn refinement_is_bitwise_identical_across_thread_counts() {
        let terms = terms_of(&[Offset, Viscous, SensorLag]);
        let truth = [0.8, 0.2, 1.6, 0.3, 0.05, 0.01];
        let m = 6;
        let ys: Vec<Vec<f64>> = (0..m)
            .map(|i| {
                let exc = Excitation {
                    samples: 64,
                    amplitude: 1.0 + (i % 2) as f64,
                    frequency: 1.0 + i as f64,
                    grid_phase: 0.3 * i as f64,
                };
                let y = augmented_output(&exc, &terms, &truth, 1.0, 0.5 + 0.1 * i as f64, 4)
                    .unwrap()
                    .y;
                // Deterministic pseudo-noise so that the fit does not end at zero cost.
                y.iter()
                    .enumerate()
                    .map(|(j, v)| v + 1e-3 * ((j * 7 + i * 13) as f64).sin())
                    .collect()
            })
            .collect();
        let exps: Vec<AugExperiment> = (0..m)
            .map(|i| AugExperiment {
                ybar: &ys[i],
                amplitude: 1.0 + (i % 2) as f64,
                frequency: 1.0 + i as f64,
                grid_phase: 0.3 * i as f64,
                weight: 1e6,
                waveform: &[],
                substeps: None,
            })
            .collect();
        let start = [0.7, 0.25, 1.8, 0.2, 0.06, 0.02];
        let gains = vec![1.1; m];
        let phases: Vec<f64> = (0..m).map(|i| 0.55 + 0.1 * i as f64).collect();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    augmented_refine(&exps, &terms, &start, &gains, &phases, &Options::default())
                        .unwrap()
                })
        };
        let (a, b) = (run(1), run(2));
        assert!(a.converged && a.iterations > 3);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.shared), bits(&b.shared));
        assert_eq!(bits(&a.gains), bits(&b.gains));
        assert_eq!(a.cost.to_bits(), b.cost.to_bits());
        assert_eq!(bits(a.fisher.as_slice()), bits(b.fisher.as_slice()));
        for (x, y) in a.shared.iter().zip(&truth) {
            assert!((x - y).abs() < 0.05 * y.abs(), "{:?}", a.shared);
        }
    }

    #[test]
    fn each_experiment_is_evaluated_at_its_own_substep_count() {
        // A coarse grid (16 samples) and a fine one (96): the outputs at the minimiser are the model's
        // at each experiment's own count, bit for bit, and a count equal to the refinement's is the
        // refinement's default.
        let terms = terms_of(&[Offset, Viscous]);
        let truth = [0.8, 0.2, 1.6, 0.3, 0.05];
        let sizes = [16usize, 96];
        let excs: Vec<Excitation> = sizes
            .iter()
            .enumerate()
            .map(|(i, &p)| Excitation {
                samples: p,
                amplitude: 1.0 + i as f64,
                frequency: 1.0 + 2.0 * i as f64,
                grid_phase: 0.2 + 0.3 * i as f64,
            })
            .collect();
        let ys: Vec<Vec<f64>> = excs
            .iter()
            .enumerate()
            .map(|(i, exc)| {
                let y = augmented_output(exc, &terms, &truth, 1.1, 0.5, 64)
                    .unwrap()
                    .y;
                y.iter()
                    .enumerate()
                    .map(|(j, v)| v + 1e-3 * ((j * 7 + i * 13) as f64).sin())
                    .collect()
            })
            .collect();
        let exps_with = |counts: [Option<usize>; 2]| -> Vec<AugExperiment> {
            (0..2)
                .map(|i| AugExperiment {
                    ybar: &ys[i],
                    amplitude: excs[i].amplitude,
                    frequency: excs[i].frequency,
                    grid_phase: excs[i].grid_phase,
                    weight: 1e6,
                    waveform: &[],
                    substeps: counts[i],
                })
                .collect()
        };
        let start = [0.7, 0.25, 1.8, 0.2, 0.06];
        let opts = Options::default();
        let fit = |counts| {
            augmented_refine(
                &exps_with(counts),
                &terms,
                &start,
                &[1.0; 2],
                &[0.45; 2],
                &opts,
            )
            .unwrap()
        };
        let own = fit([Some(8), Some(2)]);
        for (i, count) in [8, 2].into_iter().enumerate() {
            let y = augmented_output(
                &excs[i],
                &terms,
                &own.shared,
                own.gains[i],
                own.phases[i],
                count,
            )
            .unwrap()
            .y;
            assert_eq!(y, own.outputs[i], "experiment {i} at {count} substeps");
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let same = fit([Some(opts.substeps), None]);
        let default = fit([None, None]);
        assert_eq!(bits(&same.shared), bits(&default.shared));
        assert_eq!(same.cost.to_bits(), default.cost.to_bits());
        // Other counts move the minimiser, by the integration error only.
        assert_ne!(bits(&own.shared), bits(&default.shared));
        for (a, b) in own.shared.iter().zip(&default.shared) {
            assert!(
                (a - b).abs() < 1e-3 * b.abs().max(1e-2),
                "{:?} {:?}",
                own.shared,
                default.shared
            );
        }
    }

    #[test]
    fn refinement_rejects_bad_input_by_name() {
        let y = vec![0.0; 16];
        let terms = terms_of(&[SensorLag]);
        let exps = [AugExperiment {
            ybar: &y,
            amplitude: 1.0,
            frequency: 1.0,
            grid_phase: 0.0,
            weight: 1.0,
            waveform: &[],
            substeps: None,
        }];
        let go = |shared: &[f64], opts: &Options| {
            augmented_refine(&exps, &terms, shared, &[1.0], &[0.0], opts).unwrap_err()
        };
        let ok = Options::default();
        assert!(go(&[0.5, 0.1, 1.5], &ok).to_string().contains("need 4"));
        assert!(go(&[0.5, 0.1, 1.5, -0.1], &ok).to_string().contains(">= 0"));
        let bad = Options {
            mu_lo: 2.0,
            mu_hi: 1.5,
            ..ok
        };
        assert!(go(&[0.5, 0.1, 1.7, 0.1], &bad)
            .to_string()
            .contains("mu bracket"));
    }
}

//! The augmented model (`docs/design.md` 9.1, 9.3): one experiment's output with the physical
//! terms and its Jacobian, and the joint Levenberg-Marquardt over every experiment. The terms'
//! vocabulary (names, ranges) is [`crate::terms`]; the NumPy oracle is `reference/augmented.py`.
//!
//! Per sine experiment, on the averaged period's grid `theta_j = 2 pi j / P`:
//! `y_j = y0 + H_tau[w_j + k u_j + c udot_j + m uddot_j + f tanh(udot_j / (eps U omega))]_j`
//! (`eps` the terms' Coulomb smoothing, [`Terms::smoothing`])
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
//!
//! Layout: this file holds the output of one experiment (its checks and its work space of
//! columns); `augmented/` holds one job per file: `hysteresis.rs` (the loop behind the terms, plain,
//! along the input path or behind the series dashpot), `regressors.rs` (Dahl friction's loops and
//! the mechanical terms on x), `lag.rs` (the sensor lag on the period's DFT and the offset),
//! `refine.rs` (the joint refinement) and `tests.rs`.

use crate::error::{all_finite, finite, CoreError, Result};
use crate::path_loop::{
    PD_AMPLITUDE, PD_BETA, PD_DELTA, PD_DISTORT, PD_GAMMA, PD_MU, PD_PHI, PD_PINCH, PD_PLAY,
};
use crate::terms::{check_asymmetry, Place, TermKind, Terms, N_HYSTERESIS};

mod hysteresis;
mod lag;
mod refine;
mod regressors;
#[cfg(test)]
mod tests;

use hysteresis::{hysteresis, series_hysteresis};
use lag::lag_and_offset;
pub use refine::{augmented_refine, AugExperiment, AugFit, PLAY_MAX_FRACTION};
use regressors::{dahl_loops, dahl_of, on_x_regressor};

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
    augmented_output_with(
        exc,
        &[],
        MeasuredInput::default(),
        terms,
        shared,
        gain,
        phase,
        substeps,
    )
}

/// The measured input beyond its fundamental, as the mechanical terms on u see it (review 35): its
/// own harmonics `[Re c_2, Im c_2, ...]` relative to the fundamental (`u = U Re[e^{iz} + sum c_k
/// e^{ikz}]`, `z = theta_j + psi`) and its mean relative to `U`, which only the stiffness sees (a
/// spring acts on the whole displacement; a dashpot and a mass on its derivatives). Empty and 0: the
/// pure sine.
#[derive(Debug, Clone, Copy, Default)]
pub struct MeasuredInput<'a> {
    pub harmonics: &'a [f64],
    pub dc: f64,
}

impl MeasuredInput<'_> {
    /// `(u, udot, uddot)` at phase `z` for amplitude `a` and frequency `omega`, harmonics included
    /// (the mean in `u` only).
    fn at(&self, z: f64, a: f64, omega: f64) -> (f64, f64, f64) {
        let (s, c) = z.sin_cos();
        let (mut u, mut ud, mut udd) = (c + self.dc, -s, -c);
        for (i, h) in self.harmonics.chunks_exact(2).enumerate() {
            let k = (i + 2) as f64;
            let (sk, ck) = (k * z).sin_cos();
            u += h[0] * ck - h[1] * sk;
            ud -= k * (h[0] * sk + h[1] * ck);
            udd -= k * k * (h[0] * ck - h[1] * sk);
        }
        (a * u, a * omega * ud, a * omega * omega * udd)
    }
}

/// The measured input's regressors on the period's grid, as the terms on u see them: `u`, `udot`,
/// `uddot` ([`MeasuredInput::at`]) and dry friction's smoothed sign `tanh(udot / (eps |U| omega))`.
/// They depend on the experiment and the terms' smoothing only, so a refinement computes them once
/// per experiment instead of at every evaluation (nine `sin_cos` and a `tanh` per sample of a
/// distorted MR damper drive: about a tenth of its fits' time), and a model without a term on u
/// not at all. The same operations in the same order as before: the columns are equal bit for bit.
#[derive(Debug, Clone, Default)]
pub(crate) struct InputColumns {
    u: Vec<f64>,
    udot: Vec<f64>,
    uddot: Vec<f64>,
    fric: Vec<f64>,
}

impl InputColumns {
    /// The columns of `exc`'s grid for `input` and the smoothing `eps`; empty unless one of
    /// `terms` reads them ([`reads_input`]).
    pub(crate) fn new(exc: &Excitation, input: &MeasuredInput<'_>, terms: &Terms) -> Self {
        if !reads_input(terms) {
            return Self::default();
        }
        let p = exc.samples;
        let (u_amp, omega) = (exc.amplitude, exc.frequency);
        let step = 2.0 * std::f64::consts::PI / p as f64;
        let mut out = Self {
            u: Vec::with_capacity(p),
            udot: Vec::with_capacity(p),
            uddot: Vec::with_capacity(p),
            fric: Vec::with_capacity(p),
        };
        for j in 0..p {
            let th = step * j as f64 + exc.grid_phase;
            let (u, udot, uddot) = input.at(th, u_amp, omega);
            // The peak input velocity |U| omega: the smoothed sign follows sgn(udot) for either
            // sign of U.
            out.fric
                .push((udot / (terms.smoothing() * u_amp.abs() * omega)).tanh());
            out.u.push(u);
            out.udot.push(udot);
            out.uddot.push(uddot);
        }
        out
    }
}

/// Whether one of `terms` acts on the measured input u through [`InputColumns`] (a spring, a
/// dashpot, a mass or dry friction on u).
fn reads_input(terms: &Terms) -> bool {
    terms.kinds().iter().enumerate().any(|(t, &kind)| {
        terms.place(t) == Place::Usual
            && matches!(
                kind,
                TermKind::Stiffness | TermKind::Viscous | TermKind::Inertia | TermKind::Coulomb
            )
    })
}

/// [`augmented_output`] of an experiment whose measured input waveform (design.md 9.5) is
/// `waveform = [Re c_2, Im c_2, Re c_3, ...]` (relative to the fundamental; empty: a pure sine),
/// used by the `distortion` term (the waveform of x, carried through G). The mechanical terms on u
/// see `input`: the measured u with its own harmonics (and its mean, the stiffness); on x they see
/// the fundamental of x.
#[allow(clippy::too_many_arguments)]
pub fn augmented_output_with(
    exc: &Excitation,
    waveform: &[f64],
    input: MeasuredInput<'_>,
    terms: &Terms,
    shared: &[f64],
    gain: f64,
    phase: f64,
    substeps: usize,
) -> Result<AugOutput> {
    exc.validate()?;
    let columns = InputColumns::new(exc, &input, terms);
    output_on(
        exc,
        waveform,
        &columns,
        terms,
        shared,
        (gain, phase),
        substeps,
    )
}

/// [`augmented_output_with`] with the measured input's columns given (a refinement's, computed once).
pub(crate) fn output_on(
    exc: &Excitation,
    waveform: &[f64],
    input: &InputColumns,
    terms: &Terms,
    shared: &[f64],
    (gain, phase): (f64, f64),
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
                let (v, dv_da, dv_dphi) = on_x_regressor(
                    kind,
                    u_amp * gain,
                    omega,
                    step * j as f64 - phase,
                    terms.smoothing(),
                );
                f += q * v;
                col[j] = v;
                dg += q * u_amp * dv_da;
                dphi += q * dv_dphi;
                continue;
            }
            match kind {
                TermKind::Offset => offset_col = Some(1 + N_HYSTERESIS + t),
                TermKind::Stiffness => {
                    f += q * input.u[j];
                    col[j] = input.u[j];
                }
                TermKind::Viscous => {
                    f += q * input.udot[j];
                    col[j] = input.udot[j];
                }
                TermKind::Inertia => {
                    f += q * input.uddot[j];
                    col[j] = input.uddot[j];
                }
                TermKind::Coulomb => {
                    f += q * input.fric[j];
                    col[j] = input.fric[j];
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

//! Time-domain simulation of the augmented model (`docs/design.md` §9.4): the Wiener system of §1
//! with the physical terms of §9.1,
//!
//! ```text
//! y = y0 + Lag_tau[ w + k u + c udot + m uddot + f tanh(udot / (eps Vmax)) ],
//! wdot = alpha xpdot - nu (beta |xpdot| |w|^(mu-1) w + gamma xpdot |w|^mu + delta xpdot |w|^(mu-1) w),
//! xp = Play_b[x],   nu = 1 + delta_nu e,   edot = w xpdot,
//! ```
//!
//! i.e. with alpha = 1 the generalised Bouc-Wen rate of §9.2,
//! `wdot = xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))]` (the asymmetry is the
//! `sgn(w)` term of Song & Der Kiureghian, J. Eng. Mech. 132(6), 2006), driven by the play operator
//! (backlash of half-width `b`) of `x`. With `G -> alpha G` the map `delta -> delta/alpha`,
//! `b -> alpha b` leaves `y` unchanged. `u` is the plant's (undelayed) input: analytic for a sine,
//! the Catmull-Rom interpolant of §1 for samples; `Vmax = |U| omega` for a sine and the exact
//! maximum of the interpolant's `|udot|` for samples.
//!
//! The plain simulation ([`super::simulate`]) is not touched: this is a separate integrator chosen
//! once per simulation, and when no term needs a state (no asymmetry, play or lag) the plain one is
//! called and the output terms are added at the samples, so `x` and `w` stay bit-identical.
//!
//! Scheme, per RK4 step `[t, t + h]` (classical RK4 on `[xs, w, xp]`, §1):
//! - **play**: the mode is frozen over the step from its start: *up* when `x - xp >= b` and
//!   `xdot > 0`, *down* when `x - xp <= -b` and `xdot < 0`, else *dwell*. In the up (down) mode
//!   `xpdot = max(xdot, 0)` (`min(xdot, 0)`) at every stage, in the dwell mode 0. After the step
//!   `xp` is clamped into `[x - b, x + b]` (the exact play operator for a monotone step), and the
//!   clamped travel `dxp` is fed through the rate-independent path map `dw/dxp` (one RK4 step in
//!   `xp`), so that an engagement inside a dwell step moves `w` too. The scheme is fourth order
//!   between events; a step holding a reversal or an engagement costs `O(h^2)` locally, so with two
//!   of each per period the global error is `O(h^2)`, as the plain integrator's own kinks at the
//!   reversals of x (measured on a first-order G: w's error falls 4-6x per halving of h, with or
//!   without play).
//!   `b = 0` is the identity (`xp = x`, no state). `xp(0) = clamp(0, x(0) - b, x(0) + b)`.
//! - **sensor lag** `tau ysdot = F - ys`, `ys(0) = 0`: `ys` does not feed back, so it is integrated
//!   exponentially over each step (exponential time differencing, as in the final stage of Cox &
//!   Matthews' ETDRK4, J. Comput. Phys. 176, 2002) with `F` replaced by the quadratic through
//!   `F_0 = F(t)`, `F_m = F(t + h/2)`, `F_1 = F(t + h)`: `ys+ = e^-r ys + r [c_0 F_0 + c_m F_m +
//!   c_1 F_1]`, `r = h/tau`, `c_0 = phi_1 - 3 phi_2 + 4 phi_3`, `c_m = 4 phi_2 - 8 phi_3`,
//!   `c_1 = 4 phi_3 - phi_2` at `-r`. `F_0`, `F_1` use the accepted states, `w(t + h/2)` the RK4
//!   step's third-order continuous extension `w + h (5 k_1 + 4 k_2 + 4 k_3 - k_4)/24`. It is exact
//!   for the decay, stable for every `tau > 0` (explicit RK4 would blow up for `h > 2.79 tau`),
//!   tends to Simpson's weights as `r -> 0` and to `ys = F` as `r -> inf` (so a vanishing lag
//!   gives the lag-free output). `tau = 0` is no lag (`y` from `F` at the samples).
//! - **degradation** (Baber & Noori, J. Eng. Mech. 111(8), 1985, strength degradation only):
//!   the dissipated hysteretic energy `e = int w dxp` rides along as one more RK4 state
//!   (`edot = w xpdot`, `e(0) = 0`, moved with `w` along the play's clamped travel) and
//!   `nu = 1 + delta_nu e` multiplies the beta, gamma and delta terms: the loop's saturation level
//!   `(alpha/(nu (beta + gamma)))^(1/mu)` falls as energy is dissipated (§10.6).
//! - **stiffness degradation** (Baber & Noori's `eta`): `eta = 1 + delta_eta e` on the same energy
//!   state divides the whole rate, `alpha` included: the loop keeps its saturation level
//!   `(alpha/(beta + gamma))^(1/mu)` but is reached over a longer travel (a softer loop).
//! - **pinching** (Baber & Noori 1986, in Foliente's form, 1995): the rate times
//!   `h = 1 - zeta1 exp(-((w sgn(xpdot) - q w_u) / (zeta2 w_u))^2)`, `w_u` the virgin saturation
//!   level `(alpha/(beta + gamma))^(1/mu)`, the shape fixed at `q = ` [`PINCHING_CENTRE`],
//!   `zeta2 = ` [`PINCHING_WIDTH`]: a band of w just past the zero crossing after each reversal
//!   where w slips (moves slowly with x). Rate independent (h depends on the direction only), so the
//!   play's path map carries it too.
//! - **series dashpot** (Spencer, Dyke, Sain & Carlson, J. Eng. Mech. 123(3), 1997, with their
//!   `c0 = k0 = 0`): the element sits behind a dashpot in series and is driven by its own travel
//!   `d = xp - q`; the dashpot carries the element's force, `c1 qdot = w`, so with `rho = 1/c1`
//!   `ddot = xpdot - rho w` at every stage (no new state: `q` is not needed). The element's energy is
//!   `e = int w dd`. A play's clamped travel is instantaneous, so the dashpot does not move in it.
//! - the **output terms** are evaluated at the sample times (and, inside `F`, at the stage times).

use super::on_x::{linear_pass, smoothing_key, Kinematics, OnX, OnXValues};
use super::{check_dt, simulate, try_zeros, Input, Simulation, Sine, Source};
use crate::bouc_wen::{sgn, BoucWen};
use crate::error::{finite, CoreError, Result};
use crate::hermite::Hermite;
use crate::linear::{Companion, TransferFunction};
use crate::terms::{
    check_asymmetry, check_coulomb_smoothing, parse_placed, Place, TermKind, COULOMB_SMOOTHING,
    COULOMB_SMOOTHING_KEY, PINCHING_CENTRE, PINCHING_WIDTH,
};

/// Relative slack of the play's engagement test `|x - xp| >= b`: after a clamp `x - xp` equals `b`
/// only to the rounding of `x`.
const PLAY_ENGAGE_RTOL: f64 = 1e-12;

/// Below this `r = h/tau` the `phi` functions of the lag are summed as Taylor series (the closed
/// forms cancel there); [`PHI_TERMS`] terms make the truncation below `1/23! < 1e-22`.
const PHI_SERIES_BELOW: f64 = 1.0;
const PHI_TERMS: usize = 20;

/// Parameters of the §9.1 terms; an absent term is 0 (which is also what a zero parameter
/// means physically: `Play(0)` is the identity, `SensorLag(0)` no lag).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TermValues {
    /// Output offset `y0` (units of `y`).
    pub offset: f64,
    /// Parallel stiffness `k` (`[y]/[u]`).
    pub stiffness: f64,
    /// Viscous damping `c` (`[y] s/[u]`).
    pub viscous: f64,
    /// Inertia `m` (`[y] s^2/[u]`).
    pub inertia: f64,
    /// Coulomb friction level `f` (units of `y`).
    pub coulomb: f64,
    /// `eps` of `tanh(udot / (eps Vmax))`, in `(0, 0.5]`.
    pub coulomb_smoothing: f64,
    /// Sensor lag `tau` (s), `>= 0`.
    pub sensor_lag: f64,
    /// Asymmetry `delta` (`1/[w]^mu`), `|delta| < beta + gamma`.
    pub asymmetry: f64,
    /// Play half-width `b` (units of `x`), `>= 0`.
    pub play: f64,
    /// Strength degradation `delta_nu` (`1/([w] [x])`), `>= 0`: Baber-Noori
    /// `nu = 1 + delta_nu e`, `e = int w dxp` (the hysteretic energy dissipated), multiplies the
    /// beta, gamma and delta terms of the rate.
    pub degradation: f64,
    /// Stiffness degradation `delta_eta` (`1/([w] [x])`), `>= 0`: Baber-Noori
    /// `eta = 1 + delta_eta e` divides the whole rate (the same energy state as `degradation`).
    pub stiffness_degradation: f64,
    /// Pinching `zeta1` in `[0, 1)`: the rate times Foliente's `h(w, sgn xpdot)` (module header).
    pub pinching: f64,
    /// Series dashpot `rho` (`[x]/([w] s)`), `>= 0`: the element is driven by its own travel,
    /// `ddot = xpdot - rho w` (module header).
    pub series_dashpot: f64,
    /// The mechanical terms across the hysteretic element, on x (`rust/simulate/on_x.rs`).
    pub on_x: OnXValues,
}

impl Default for TermValues {
    fn default() -> Self {
        Self {
            offset: 0.0,
            stiffness: 0.0,
            viscous: 0.0,
            inertia: 0.0,
            coulomb: 0.0,
            coulomb_smoothing: COULOMB_SMOOTHING,
            sensor_lag: 0.0,
            asymmetry: 0.0,
            play: 0.0,
            degradation: 0.0,
            stiffness_degradation: 0.0,
            pinching: 0.0,
            series_dashpot: 0.0,
            on_x: OnXValues::default(),
        }
    }
}

impl TermValues {
    /// Values from `(code name, value)` pairs (the code names of [`TermKind`] that act in a
    /// simulation, at their usual place or on x as `"<code name>@x"`, and
    /// [`COULOMB_SMOOTHING_KEY`] and the on-x friction's [`smoothing_key`]); missing ones are
    /// absent.
    ///
    /// Errors: [`CoreError::InvalidParameter`] for an unknown name or place, or a term without a
    /// simulation form. Values are checked by [`TermValues::validate`].
    pub fn from_named<'a>(pairs: impl IntoIterator<Item = (&'a str, f64)>) -> Result<Self> {
        let mut t = Self::default();
        let on_x_smoothing = smoothing_key();
        for (name, v) in pairs {
            let slot = if name == COULOMB_SMOOTHING_KEY {
                &mut t.coulomb_smoothing
            } else if name == on_x_smoothing {
                &mut t.on_x.coulomb_smoothing
            } else {
                let (kind, place) = parse_placed(name)?;
                let slot = match place {
                    Place::Usual => t.slot(kind),
                    // `parse_placed` admits only the mechanical terms on x.
                    Place::X => t.on_x.slot(kind),
                };
                slot.ok_or_else(|| {
                    CoreError::InvalidParameter(format!(
                        "term {name:?} has no time-domain form (steady-loop model only); a \
                         simulation takes every other term"
                    ))
                })?
            };
            *slot = v;
        }
        Ok(t)
    }

    /// The value of `kind`, `None` for a term the simulation does not have.
    pub fn get(&self, kind: TermKind) -> Option<f64> {
        let mut t = *self;
        t.slot(kind).map(|v| *v)
    }

    /// Where `kind`'s value is kept, `None` for a term the simulation does not have.
    fn slot(&mut self, kind: TermKind) -> Option<&mut f64> {
        match kind {
            TermKind::Offset => Some(&mut self.offset),
            TermKind::Stiffness => Some(&mut self.stiffness),
            TermKind::Viscous => Some(&mut self.viscous),
            TermKind::Inertia => Some(&mut self.inertia),
            TermKind::Coulomb => Some(&mut self.coulomb),
            TermKind::SensorLag => Some(&mut self.sensor_lag),
            TermKind::Asymmetry => Some(&mut self.asymmetry),
            TermKind::Play => Some(&mut self.play),
            TermKind::Degradation => Some(&mut self.degradation),
            TermKind::StiffnessDegradation => Some(&mut self.stiffness_degradation),
            TermKind::Pinching => Some(&mut self.pinching),
            TermKind::SeriesDashpot => Some(&mut self.series_dashpot),
            // Steady-loop model only (no time-domain form yet).
            TermKind::Distortion | TermKind::Dahl | TermKind::DahlSigma => None,
        }
    }

    /// Checks the §9.1 admissibility against the hysteresis `bw`: all finite, `tau >= 0`,
    /// `b >= 0`, `delta_nu >= 0`, `0 < eps <= 0.5`, `|delta| < beta + gamma`.
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`].
    pub fn validate(&self, bw: &BoucWen) -> Result<()> {
        let values = || {
            TermKind::ALL
                .into_iter()
                .filter_map(|k| self.get(k).map(|v| (k, v)))
        };
        for (kind, v) in values() {
            finite(kind.name(), v)?;
        }
        check_coulomb_smoothing(self.coulomb_smoothing)?;
        for (kind, v) in values() {
            kind.check_value(v)?;
        }
        self.on_x.validate()?;
        check_asymmetry(self.asymmetry, bw.beta(), bw.gamma())
    }

    /// `"name = value, ..."` of the present (non-zero) terms, for error messages.
    pub fn describe(&self) -> String {
        let usual = TermKind::ALL.into_iter().filter_map(|k| {
            self.get(k)
                .filter(|v| *v != 0.0)
                .map(|v| (k.name().to_string(), v))
        });
        let mut on_x = self.on_x;
        let placed = [
            TermKind::Stiffness,
            TermKind::Viscous,
            TermKind::Inertia,
            TermKind::Coulomb,
        ]
        .into_iter()
        .filter_map(|k| {
            let v = *on_x.slot(k)?;
            (v != 0.0).then(|| (super::on_x::placed_name(k), v))
        })
        .collect::<Vec<_>>();
        let all: Vec<String> = usual
            .chain(placed)
            .map(|(name, v)| format!("{name} = {v:e}"))
            .collect();
        if all.is_empty() {
            "none".into()
        } else {
            all.join(", ")
        }
    }

    /// `true` when a term needs a state or changes `w` (asymmetry, play, sensor lag,
    /// degradation of strength or stiffness, pinching).
    pub fn is_dynamic(&self) -> bool {
        self.asymmetry != 0.0
            || self.play > 0.0
            || self.sensor_lag > 0.0
            || self.degradation > 0.0
            || self.stiffness_degradation > 0.0
            || self.pinching > 0.0
            || self.series_dashpot > 0.0
    }
}

/// Simulated signals with terms, on the output grid `t_k = k dt`.
#[derive(Debug, Clone, PartialEq)]
pub struct TermSimulation {
    /// Linear output `x_k` (units of `x`).
    pub x: Vec<f64>,
    /// Hysteresis output `w_k` (driven by the played `xp`).
    pub w: Vec<f64>,
    /// Measured output `y_k` before noise (units of `y`).
    pub y: Vec<f64>,
}

/// Simulates the augmented model (§9.4): `tf` -> play -> generalised Bouc-Wen `bw` + `delta`,
/// plus the output terms and the sensor lag, driven by `input`.
///
/// Grid, `substeps` and the initial state as in [`simulate`]; `xp(0) = clamp(0, x(0) ± b)`,
/// `ys(0) = 0`. Returns `x`, `w`, `y`, each of length `n_samples`.
///
/// Errors: those of [`simulate`], then [`TermValues::validate`]'s.
pub fn simulate_with_terms(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    input: Input<'_>,
    dt: f64,
    n_samples: usize,
    substeps: usize,
) -> Result<TermSimulation> {
    input.validate()?;
    let dt = check_dt(dt)?;
    if substeps < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "substeps = {substeps} must be >= 1"
        )));
    }
    if n_samples < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "n_samples = {n_samples} must be >= 1"
        )));
    }
    terms.validate(bw)?;
    match input {
        Input::Sine { amplitude, omega } => {
            let src = Sine {
                amplitude,
                omega,
                neg_amplitude_omega: -amplitude * omega,
            };
            run(tf, bw, terms, input, &src, dt, n_samples, substeps)
        }
        Input::Sampled { u } => {
            let src = Hermite::new(u, dt);
            run(tf, bw, terms, input, &src, dt, n_samples, substeps)
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn run<S: Derivatives>(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    input: Input<'_>,
    src: &S,
    dt: f64,
    n_samples: usize,
    substeps: usize,
) -> Result<TermSimulation> {
    let mech = Mechanical::new(terms, src);
    let comp = tf.realize();
    let delay = tf.delay();
    let delayed = |t: f64| delayed_with_second(src, delay, t);
    let mut on_x = if terms.on_x.is_active() {
        let peak = if terms.on_x.coulomb == 0.0 {
            0.0 // no friction on x: its scale is not used
        } else if let Some(steady) = src.steady_x_peak_rate(tf) {
            steady
        } else {
            let mut kin = Kinematics::new(&comp);
            let mut peak = 0.0f64;
            linear_pass(&comp, delayed, dt, n_samples, substeps, |_, t, xs| {
                peak = peak.max(kin.at(xs, delayed(t)).1.abs());
            });
            peak
        };
        Some(OnX::new(terms.on_x, &comp, peak))
    } else {
        None
    };
    if !terms.is_dynamic() {
        // Nothing changes x or w: the plain integrator, untouched, and the terms at the samples (the
        // terms on x from the linear part's states, stepped alone as the plain integrator steps them).
        let Simulation { x, w } = simulate(tf, bw, input, dt, n_samples, substeps)?;
        let mut y = try_zeros(n_samples)?;
        for (k, (yk, wk)) in y.iter_mut().zip(&w).enumerate() {
            *yk = wk + mech.at(k as f64 * dt);
        }
        if let Some(on_x) = on_x.as_mut() {
            linear_pass(&comp, delayed, dt, n_samples, substeps, |k, t, xs| {
                y[k] += on_x.at(xs, delayed(t));
            });
        }
        for yk in y.iter_mut() {
            *yk += terms.offset; // IEEE addition commutes: the same bits as offset + F
        }
        let out = TermSimulation { x, w, y };
        check_blow_up(tf, bw, terms, dt, &out)?;
        return Ok(out);
    }
    let mut out = TermSimulation {
        x: try_zeros(n_samples)?,
        w: try_zeros(n_samples)?,
        y: try_zeros(n_samples)?,
    };
    // Pinching's band in units of w: centre q w_u and width zeta2 w_u, w_u the virgin saturation level.
    let w_u = (bw.alpha() / (bw.beta() + bw.gamma())).powf(1.0 / bw.mu());
    let sys = Augmented {
        comp: &comp,
        alpha: bw.alpha(),
        beta: bw.beta(),
        gamma: bw.gamma(),
        mu: bw.mu(),
        delta: terms.asymmetry,
        degradation: terms.degradation,
        stiffness_degradation: terms.stiffness_degradation,
        pinch: Pinch {
            zeta1: terms.pinching,
            centre: PINCHING_CENTRE * w_u,
            width: PINCHING_WIDTH * w_u,
        },
        delay,
        src,
        mech,
    };
    sys.integrate(bw.w0(), terms, dt, substeps, &mut on_x, &mut out);
    crate::cancel::checkpoint()?;
    check_blow_up(tf, bw, terms, dt, &out)?;
    Ok(out)
}

/// The delayed input `(v, vdot, vddot)` at time `t` (0 before the delay has elapsed).
#[inline]
fn delayed_with_second<S: Derivatives>(src: &S, delay: f64, t: f64) -> (f64, f64, f64) {
    let tau = t - delay;
    if tau < 0.0 {
        (0.0, 0.0, 0.0)
    } else {
        let (v, vdot) = src.at(tau);
        (v, vdot, src.second(tau))
    }
}

/// A non-finite `x`, `w` or `y` is the model's blow-up, not the caller's data (the inputs were
/// checked finite): name the parameters, the terms and where it happened (as
/// `simulate::check_blow_up` for the plain model).
///
/// Errors: [`CoreError::NonFinite`].
fn check_blow_up(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    dt: f64,
    out: &TermSimulation,
) -> Result<()> {
    let first = [("x", &out.x), ("w", &out.w), ("y", &out.y)]
        .into_iter()
        .filter_map(|(name, v)| v.iter().position(|v| !v.is_finite()).map(|k| (k, name)))
        .min();
    let Some((k, signal)) = first else {
        return Ok(());
    };
    Err(CoreError::NonFinite(format!(
        "the simulation blew up: {signal} is not finite from sample {k} (t = {:.6e} s) on; the \
         model parameters (alpha = {:e}, beta = {:e}, gamma = {:e}, mu = {}, w0 = {:e}, G = \
         {:?}/{:?}) with the terms ({}) or the input level make the state overflow; use term \
         values and parameters of moderate size, a smaller amplitude or a finer step (substeps)",
        k as f64 * dt,
        bw.alpha(),
        bw.beta(),
        bw.gamma(),
        bw.mu(),
        bw.w0(),
        tf.num(),
        tf.den(),
        terms.describe(),
    )))
}

/// The input's second derivative and peak rate, beyond the `(u, udot)` of [`Source`].
trait Derivatives: Source {
    /// `uddot(tau)` (units of u per s^2), `tau >= 0`.
    fn second(&self, tau: f64) -> f64;
    /// `Vmax = max |udot|` over `t >= 0` (units of u per s).
    fn peak_rate(&self) -> f64;
    /// The steady peak of `|xdot|` through `tf` where the input has one (a sine:
    /// `|U| |G(j omega)| omega`); `None` for samples (`rust/simulate/on_x.rs`).
    fn steady_x_peak_rate(&self, tf: &TransferFunction) -> Option<f64>;
}

impl Derivatives for Sine {
    fn second(&self, tau: f64) -> f64 {
        self.neg_amplitude_omega * self.omega * (self.omega * tau).cos()
    }

    fn peak_rate(&self) -> f64 {
        self.amplitude.abs() * self.omega
    }

    fn steady_x_peak_rate(&self, tf: &TransferFunction) -> Option<f64> {
        let (re, im) = tf.freq_response(self.omega);
        Some(self.amplitude.abs() * re.hypot(im) * self.omega)
    }
}

impl Derivatives for Hermite<'_> {
    /// The right-hand second derivative of the cubic on `[t_k, t_{k+1})` (it jumps at the knots);
    /// 0 past the last sample.
    fn second(&self, tau: f64) -> f64 {
        Hermite::second(self, tau)
    }

    fn steady_x_peak_rate(&self, _tf: &TransferFunction) -> Option<f64> {
        None
    }

    /// Exact: on each interval `udot` is the quadratic `A s^2 + B s + m_k` in `s = (t - t_k)/dt`,
    /// so its extremes are the knot slopes and an interior vertex.
    fn peak_rate(&self) -> f64 {
        let mut peak = 0.0f64;
        for k in 0..self.u.len() - 1 {
            let (m0, m1) = (self.m[k], self.m[k + 1]);
            let slope = (self.u[k + 1] - self.u[k]) / self.dt;
            let a = 3.0 * (m0 + m1) - 6.0 * slope;
            let b = 6.0 * slope - 4.0 * m0 - 2.0 * m1;
            peak = peak.max(m0.abs()).max(m1.abs());
            if a != 0.0 {
                let s = -b / (2.0 * a);
                if s > 0.0 && s < 1.0 {
                    peak = peak.max((m0 + s * (b + s * a)).abs());
                }
            }
        }
        peak
    }
}

/// The output terms on the measured input: `k u + c udot + m uddot + f tanh(udot/(eps Vmax))`.
struct Mechanical<'a, S> {
    src: &'a S,
    stiffness: f64,
    viscous: f64,
    inertia: f64,
    coulomb: f64,
    /// `eps Vmax`; 0 when the input never moves (then the friction term is 0).
    velocity_scale: f64,
}

impl<'a, S: Derivatives> Mechanical<'a, S> {
    fn new(terms: &TermValues, src: &'a S) -> Self {
        Self {
            src,
            stiffness: terms.stiffness,
            viscous: terms.viscous,
            inertia: terms.inertia,
            coulomb: terms.coulomb,
            velocity_scale: terms.coulomb_smoothing * src.peak_rate(),
        }
    }

    /// The terms at time `t >= 0` (units of y).
    fn at(&self, t: f64) -> f64 {
        let (u, udot) = self.src.at(t);
        let uddot = self.src.second(t);
        let friction = if self.velocity_scale > 0.0 {
            self.coulomb * (udot / self.velocity_scale).tanh()
        } else {
            0.0
        };
        self.stiffness * u + self.viscous * udot + self.inertia * uddot + friction
    }
}

/// Play mode of one RK4 step (frozen from the step's start).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Up,
    Down,
    Dwell,
}

impl Mode {
    #[inline]
    fn rate(self, xdot: f64) -> f64 {
        match self {
            Mode::Up => xdot.max(0.0),
            Mode::Down => xdot.min(0.0),
            Mode::Dwell => 0.0,
        }
    }
}

/// Weights of the exponential lag step (module header): `(e^-r, r c_0, r c_m, r c_1)`.
fn lag_weights(r: f64) -> (f64, f64, f64, f64) {
    if !r.is_finite() {
        // tau so small that h/tau overflows: the sensor follows F at once.
        return (0.0, 0.0, 0.0, 1.0);
    }
    let z = -r;
    let (p1, p2, p3) = if r < PHI_SERIES_BELOW {
        // phi_k(z) = sum_j z^j / (j + k)!, summed from the smallest term.
        let mut fact = [1.0f64; PHI_TERMS + 4];
        for i in 1..fact.len() {
            fact[i] = fact[i - 1] * i as f64;
        }
        let phi = |k: usize| {
            let mut acc = 0.0;
            for j in (0..PHI_TERMS).rev() {
                acc = acc * z + 1.0 / fact[j + k];
            }
            acc
        };
        (phi(1), phi(2), phi(3))
    } else {
        let p1 = z.exp_m1() / z;
        let p2 = (p1 - 1.0) / z;
        let p3 = (p2 - 0.5) / z;
        (p1, p2, p3)
    };
    (
        z.exp(),
        r * (p1 - 3.0 * p2 + 4.0 * p3),
        r * (4.0 * p2 - 8.0 * p3),
        r * (4.0 * p3 - p2),
    )
}

/// Foliente's pinching factor with its fixed shape in units of w (module header).
#[derive(Clone, Copy)]
struct Pinch {
    zeta1: f64,
    centre: f64,
    width: f64,
}

impl Pinch {
    /// `h = 1 - zeta1 exp(-((w sgn(xpdot) - centre) / width)^2)`; the rate is 0 where `xpdot = 0`
    /// whatever h, so the sign of 0 does not matter.
    #[inline]
    fn factor(&self, w: f64, xpdot: f64) -> f64 {
        let z = (w * sgn(xpdot) - self.centre) / self.width;
        1.0 - self.zeta1 * (-z * z).exp()
    }
}

/// The augmented right-hand side: linear part, generalised Bouc-Wen with `delta`, the input.
struct Augmented<'a, S> {
    comp: &'a Companion,
    alpha: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    /// `delta_nu` of `nu = 1 + delta_nu e` (0: no energy state is needed, `nu = 1`).
    degradation: f64,
    /// `delta_eta` of `eta = 1 + delta_eta e` dividing the whole rate (0: `eta = 1`, not applied).
    stiffness_degradation: f64,
    pinch: Pinch,
    delay: f64,
    src: &'a S,
    mech: Mechanical<'a, S>,
}

impl<S: Derivatives> Augmented<'_, S> {
    /// Delayed input `(v, vdot)` at time `t` (0 before the delay has elapsed).
    #[inline]
    fn delayed(&self, t: f64) -> (f64, f64) {
        let tau = t - self.delay;
        if tau < 0.0 {
            (0.0, 0.0)
        } else {
            self.src.at(tau)
        }
    }

    /// `wdot = alpha xpdot - nu (beta |xpdot| |w|^(mu-1) w + gamma xpdot |w|^mu
    /// + delta xpdot |w|^(mu-1) w)`, `nu = 1 + delta_nu e` (positively homogeneous of degree 1 in
    /// `xpdot`, so it is also `dw` for a path increment `dxp`).
    #[inline]
    fn rate(&self, xpdot: f64, w: f64, e: f64) -> f64 {
        let wmu = w.abs().powf(self.mu);
        let sw = sgn(w);
        let nu = 1.0 + self.degradation * e;
        // nu multiplies each term (not their sum) so that nu = 1 rounds exactly as before.
        let mut r = self.alpha * xpdot
            - nu * (self.beta * xpdot.abs() * sw * wmu)
            - nu * (self.gamma * xpdot * wmu)
            - nu * (self.delta * xpdot * sw * wmu);
        // Applied only when present, so that the other terms' runs round exactly as before.
        if self.stiffness_degradation != 0.0 {
            r /= 1.0 + self.stiffness_degradation * e;
        }
        if self.pinch.zeta1 != 0.0 {
            r *= self.pinch.factor(w, xpdot);
        }
        r
    }

    /// `xsdot` into `dxs` and `xdot`, at state `xs` and delayed input `(v, vdot)`.
    #[inline]
    fn linear(&self, xs: &[f64], (v, vdot): (f64, f64), dxs: &mut [f64]) -> f64 {
        self.comp.state_derivative(xs, v, dxs);
        self.comp.output_row(dxs) + self.comp.d * vdot
    }

    /// `(w, e)` moved along the hysteresis path by the play's clamped travel `dxp` (one RK4 step
    /// of `dw/dsigma = rate(dxp, w, e)`, `de/dsigma = w dxp`, `sigma in [0, 1]`).
    fn path(&self, w: f64, e: f64, dxp: f64) -> (f64, f64) {
        let k1 = self.rate(dxp, w, e);
        let (w2, e2) = (w + 0.5 * k1, e + 0.5 * w * dxp);
        let k2 = self.rate(dxp, w2, e2);
        let (w3, e3) = (w + 0.5 * k2, e + 0.5 * w2 * dxp);
        let k3 = self.rate(dxp, w3, e3);
        let (w4, e4) = (w + k3, e + w3 * dxp);
        let k4 = self.rate(dxp, w4, e4);
        (
            w + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0,
            e + (w + 2.0 * w2 + 2.0 * w3 + w4) * dxp / 6.0,
        )
    }

    /// `w + mech(t)`, plus the terms on x at state `xs` when present: the lag's input `F` and,
    /// without a lag, the output before the offset.
    #[inline]
    fn forcing(&self, w: f64, t: f64, xs: &[f64], on_x: &mut Option<OnX<'_>>) -> f64 {
        let f = w + self.mech.at(t);
        match on_x {
            Some(o) => f + o.at(xs, delayed_with_second(self.src, self.delay, t)),
            None => f,
        }
    }

    fn integrate(
        &self,
        w0: f64,
        terms: &TermValues,
        dt: f64,
        substeps: usize,
        on_x: &mut Option<OnX<'_>>,
        out: &mut TermSimulation,
    ) {
        let n = self.comp.order();
        let d = self.comp.d;
        let h = dt / substeps as f64;
        let half_h = 0.5 * h;
        let h_sixth = h / 6.0;
        let b = terms.play;
        let has_play = b > 0.0;
        let tau = terms.sensor_lag;
        let has_lag = tau > 0.0;
        let rho = terms.series_dashpot;
        let (decay, l0, lm, l1) = if has_lag {
            lag_weights(h / tau)
        } else {
            (0.0, 0.0, 0.0, 0.0)
        };

        let mut xs = vec![0.0; n];
        let mut w = w0;
        // Dissipated energy `e = int w dxp` (stays 0 without degradation: `nu = 1` exactly).
        let mut en = 0.0f64;
        let x0 = self.comp.output_row(&xs) + d * self.delayed(0.0).0;
        let mut xp = 0.0f64.max(x0 - b).min(x0 + b);
        let mut ys = 0.0;
        let (mut k1, mut k2, mut k3, mut k4, mut tmp) = (
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
        );
        // The state at the step's middle for the terms on x in the lag's F (continuous extension).
        let mut xs_mid = vec![0.0; n];
        let last = out.x.len() - 1;
        for k in 0..out.x.len() {
            let t = k as f64 * dt;
            out.x[k] = self.comp.output_row(&xs) + d * self.delayed(t).0;
            out.w[k] = w;
            out.y[k] = terms.offset
                + if has_lag {
                    ys
                } else {
                    self.forcing(w, t, &xs, on_x)
                };
            if k == last {
                break;
            }
            for s in 0..substeps {
                let ts = t + s as f64 * h;
                let (tm, te) = (ts + half_h, ts + h);
                let (in1, inm, in4) = (self.delayed(ts), self.delayed(tm), self.delayed(te));

                let xdot1 = self.linear(&xs, in1, &mut k1);
                let mode = if has_play {
                    let x = self.comp.output_row(&xs) + d * in1.0;
                    let e = x - xp;
                    let slack = PLAY_ENGAGE_RTOL * (b + x.abs());
                    if xdot1 > 0.0 && e >= b - slack {
                        Mode::Up
                    } else if xdot1 < 0.0 && e <= -b + slack {
                        Mode::Down
                    } else {
                        Mode::Dwell
                    }
                } else {
                    Mode::Up // unused: without play xpdot = xdot
                };
                let played = |xdot: f64| if has_play { mode.rate(xdot) } else { xdot };

                // The element's travel rate behind the series dashpot (`rho = 0`: `p - 0 = p`).
                let element = |p: f64, w: f64| p - rho * w;
                let p1 = played(xdot1);
                let d1 = element(p1, w);
                let kw1 = self.rate(d1, w, en);
                let ke1 = w * d1;
                let (w2, e2) = (w + half_h * kw1, en + half_h * ke1);
                axpy(&mut tmp, &xs, half_h, &k1);
                let p2 = played(self.linear(&tmp, inm, &mut k2));
                let d2 = element(p2, w2);
                let kw2 = self.rate(d2, w2, e2);
                let ke2 = w2 * d2;
                let (w3, e3) = (w + half_h * kw2, en + half_h * ke2);
                axpy(&mut tmp, &xs, half_h, &k2);
                let p3 = played(self.linear(&tmp, inm, &mut k3));
                let d3 = element(p3, w3);
                let kw3 = self.rate(d3, w3, e3);
                let ke3 = w3 * d3;
                let (w4, e4) = (w + h * kw3, en + h * ke3);
                axpy(&mut tmp, &xs, h, &k3);
                let p4 = played(self.linear(&tmp, in4, &mut k4));
                let d4 = element(p4, w4);
                let kw4 = self.rate(d4, w4, e4);
                let ke4 = w4 * d4;

                // Third-order continuous extension of the RK4 step at its midpoint.
                let w_mid = w + h * (5.0 * kw1 + 4.0 * (kw2 + kw3) - kw4) / 24.0;
                let f0 = if has_lag {
                    if on_x.is_some() {
                        for ((((m, x), a), b2), (c3, d4)) in xs_mid
                            .iter_mut()
                            .zip(&xs)
                            .zip(&k1)
                            .zip(&k2)
                            .zip(k3.iter().zip(&k4))
                        {
                            *m = x + h * (5.0 * a + 4.0 * (b2 + c3) - d4) / 24.0;
                        }
                    }
                    self.forcing(w, ts, &xs, on_x)
                } else {
                    0.0
                };
                for ((((x, a), b2), c3), d4) in xs.iter_mut().zip(&k1).zip(&k2).zip(&k3).zip(&k4) {
                    *x += h_sixth * (a + 2.0 * b2 + 2.0 * c3 + d4);
                }
                w += h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4);
                en += h_sixth * (ke1 + 2.0 * ke2 + 2.0 * ke3 + ke4);
                if has_play {
                    xp += h_sixth * (p1 + 2.0 * p2 + 2.0 * p3 + p4);
                    let x_end = self.comp.output_row(&xs) + d * in4.0;
                    let clamped = xp.max(x_end - b).min(x_end + b);
                    let travel = clamped - xp;
                    if travel != 0.0 {
                        (w, en) = self.path(w, en, travel);
                    }
                    xp = clamped;
                }
                if has_lag {
                    let fm = self.forcing(w_mid, tm, &xs_mid, on_x);
                    let f1 = self.forcing(w, te, &xs, on_x);
                    ys = decay * ys + (l0 * f0 + lm * fm + l1 * f1);
                }
            }
        }
    }
}

/// `xs + k * hk`, elementwise into `out` (all of the same length).
#[inline]
fn axpy(out: &mut [f64], xs: &[f64], hk: f64, k: &[f64]) {
    for ((o, x), ki) in out.iter_mut().zip(xs).zip(k) {
        *o = x + hk * ki;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn sine(amplitude: f64, omega: f64) -> Input<'static> {
        Input::Sine { amplitude, omega }
    }

    fn plant() -> (TransferFunction, BoucWen) {
        (
            TransferFunction::new(&[1.0], &[0.2, 1.0], 0.05).unwrap(),
            BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap(),
        )
    }

    #[test]
    fn without_dynamic_terms_x_and_w_are_the_plain_ones() {
        let (tf, bw) = plant();
        let terms = TermValues {
            offset: 0.3,
            stiffness: 0.5,
            viscous: 0.1,
            inertia: 0.01,
            coulomb: 0.2,
            ..TermValues::default()
        };
        let (u, om, dt) = (1.3, 2.0, 0.02);
        let a = simulate(&tf, &bw, sine(u, om), dt, 400, 3).unwrap();
        let b = simulate_with_terms(&tf, &bw, &terms, sine(u, om), dt, 400, 3).unwrap();
        assert_eq!((a.x, a.w.clone()), (b.x, b.w));
        for k in 0..400 {
            let t = k as f64 * dt;
            let (c, s) = ((om * t).cos(), (om * t).sin());
            let extra = 0.5 * u * c - 0.1 * u * om * s - 0.01 * u * om * om * c
                + 0.2 * (-u * om * s / (0.01 * u * om)).tanh();
            assert_relative_eq!(b.y[k], 0.3 + a.w[k] + extra, epsilon = 1e-13);
        }
    }

    #[test]
    fn terms_on_x_follow_the_linear_part_and_leave_x_and_w_alone() {
        // A resonant G with a delay: after the transient, the terms on x are
        // Re[(k + c j w - m w^2) G(j w) U e^{j w t}] and friction follows sgn(xdot).
        let tf = TransferFunction::new(&[1.0], &[0.05, 0.1, 1.0], 0.073).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap();
        let on_x = OnXValues {
            stiffness: 0.4,
            viscous: 0.05,
            inertia: 0.01,
            ..OnXValues::default()
        };
        let terms = TermValues {
            on_x,
            offset: 0.1,
            ..TermValues::default()
        };
        let (u, om, dt, n) = (1.3, 3.0, 0.01, 4000);
        let a = simulate(&tf, &bw, sine(u, om), dt, n, 3).unwrap();
        let b = simulate_with_terms(&tf, &bw, &terms, sine(u, om), dt, n, 3).unwrap();
        assert_eq!((&a.x, &a.w), (&b.x, &b.w));
        let (re, im) = tf.freq_response(om);
        let g = nalgebra::Complex::new(re, im);
        let factor = nalgebra::Complex::new(0.4 - 0.01 * om * om, 0.05 * om);
        for k in 3000..n {
            let t = k as f64 * dt;
            let e = nalgebra::Complex::from_polar(u, om * t);
            assert_relative_eq!(b.y[k] - 0.1 - b.w[k], (factor * g * e).re, epsilon = 1e-7);
            // x itself is the plain one: k x is its share.
        }
        // The augmented integrator (forced by a vanishing lag: ys = F) computes the same terms
        // from its own state, to rounding (the delay is off the grid: at t = delay the input
        // steps from 0 to U and xddot with it, and the two paths' stage times round apart).
        let lagged = TermValues {
            sensor_lag: 1e-300,
            ..terms
        };
        let c = simulate_with_terms(&tf, &bw, &lagged, sine(u, om), dt, n, 3).unwrap();
        for k in 1..n {
            assert_relative_eq!(c.y[k], b.y[k], epsilon = 1e-12);
        }
        // Friction on x: +f where xdot > 0 well beyond eps |A| omega, -f where below.
        let fric = TermValues {
            on_x: OnXValues {
                coulomb: 0.3,
                coulomb_smoothing: 0.02,
                ..OnXValues::default()
            },
            ..TermValues::default()
        };
        let f = simulate_with_terms(&tf, &bw, &fric, sine(u, om), dt, n, 3).unwrap();
        let peak = u * g.norm() * om;
        for k in 3000..n {
            let t = k as f64 * dt;
            let xdot =
                (nalgebra::Complex::new(0.0, om) * g * nalgebra::Complex::from_polar(u, om * t)).re;
            if xdot.abs() > 0.2 * peak {
                assert_relative_eq!(f.y[k] - f.w[k], 0.3 * xdot.signum(), epsilon = 1e-6);
            }
        }
    }

    #[test]
    fn a_blow_up_with_terms_names_the_terms_not_the_data() {
        let (tf, bw) = plant();
        let terms = TermValues {
            degradation: 1e300,
            ..TermValues::default()
        };
        let e = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 2.0), 0.05, 400, 2).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("blew up") && msg.contains("degradation = 1e300"),
            "{msg}"
        );
        // A term that overflows y alone (no state): blamed too.
        let terms = TermValues {
            on_x: OnXValues {
                inertia: 1e308,
                ..OnXValues::default()
            },
            ..TermValues::default()
        };
        let e = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 30.0), 0.005, 400, 2).unwrap_err();
        assert!(e.to_string().contains("inertia@x = 1e308"), "{e}");
    }

    #[test]
    fn zero_dynamic_terms_reproduce_the_plain_path() {
        // delta = 0 and b = 0 on the augmented integrator: only rounding apart from simulate().
        let (tf, bw) = plant();
        let terms = TermValues {
            sensor_lag: 1e-300, // forces the augmented path; h/tau overflows -> ys = F
            ..TermValues::default()
        };
        let a = simulate(&tf, &bw, sine(1.0, 3.0), 0.01, 600, 2).unwrap();
        let b = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 3.0), 0.01, 600, 2).unwrap();
        for k in 0..600 {
            assert_relative_eq!(a.x[k], b.x[k], epsilon = 1e-14);
            assert_relative_eq!(a.w[k], b.w[k], epsilon = 1e-13);
        }
        // with ys = F (after the first sample, where ys(0) = 0)
        for k in 1..600 {
            assert_relative_eq!(b.y[k], b.w[k], epsilon = 1e-13);
        }
    }

    #[test]
    fn lag_weights_limits() {
        // r -> 0: Simpson's weights (1, 4, 1)/6 scaled by r.
        let r = 1e-6;
        let (e, c0, cm, c1) = lag_weights(r);
        assert_relative_eq!(e, (-r).exp(), max_relative = 1e-15);
        assert_relative_eq!(c0 / r, 1.0 / 6.0, max_relative = 1e-5);
        assert_relative_eq!(cm / r, 2.0 / 3.0, max_relative = 1e-5);
        assert_relative_eq!(c1 / r, 1.0 / 6.0, max_relative = 1e-5);
        // Exact for quadratic F, on both sides of the series switch. Constant F = 1:
        // ys+ = e ys + (1 - e). Linear F = s/h from ys(0) = 0: 1 - (1 - e^-r)/r. Quadratic
        // F = (s/h)^2: 1 - 2/r + 2 (1 - e^-r)/r^2.
        for r in [0.3, 0.999, 1.0, 2.5, 40.0] {
            let (e, c0, cm, c1) = lag_weights(r);
            assert_relative_eq!(c0 + cm + c1, 1.0 - e, max_relative = 1e-13);
            assert_relative_eq!(0.5 * cm + c1, 1.0 - (1.0 - e) / r, max_relative = 1e-13);
            let quad = 1.0 - 2.0 / r + 2.0 * (1.0 - e) / (r * r);
            assert_relative_eq!(0.25 * cm + c1, quad, max_relative = 1e-12);
        }
        assert_eq!(lag_weights(f64::INFINITY), (0.0, 0.0, 0.0, 1.0));
    }

    #[test]
    fn hermite_second_derivative_and_peak_rate() {
        // A cubic on the interior is not reproduced by Catmull-Rom, but a quadratic is:
        // u = t^2 gives uddot = 2 in the interior intervals and max |udot| = 2 t at the end slope.
        let dt = 0.1;
        let u: Vec<f64> = (0..30).map(|k| (k as f64 * dt).powi(2)).collect();
        let src = Hermite::new(&u, dt);
        for k in 1..27 {
            for s in [0.0, 0.25, 0.5, 0.9] {
                assert_relative_eq!(src.second((k as f64 + s) * dt), 2.0, epsilon = 1e-9);
            }
        }
        assert_eq!(src.second(40.0), 0.0);
        // Largest slope: on the last interval, between the central slope 5.6 and the one-sided
        // end slope 5.7 the cubic's slope peaks at its vertex, 5.7 + 1/30 (by hand).
        assert_relative_eq!(src.peak_rate(), 5.7 + 1.0 / 30.0, max_relative = 1e-12);
        // A sine's peak comes from interior vertices: it bounds a dense scan of the interpolant's
        // slope and is attained by it, and it is U omega up to the Catmull-Rom slope error
        // (omega dt)^2/6 = 1.5e-4.
        let (amp, om, dt) = (2.0, 3.0, 0.01);
        let us: Vec<f64> = (0..400).map(|k| amp * (om * k as f64 * dt).cos()).collect();
        let src = Hermite::new(&us, dt);
        let scan = (0..400_000)
            .map(|i| src.at(i as f64 * dt / 1000.0).1.abs())
            .fold(0.0, f64::max);
        assert!(
            src.peak_rate() >= scan * (1.0 - 1e-14),
            "{} < {scan}",
            src.peak_rate()
        );
        assert_relative_eq!(src.peak_rate(), scan, max_relative = 1e-7);
        assert_relative_eq!(src.peak_rate(), amp * om, max_relative = 2e-4);
        let s = Sine {
            amplitude: -amp,
            omega: om,
            neg_amplitude_omega: amp * om,
        };
        assert_eq!(s.peak_rate(), amp * om);
    }

    #[test]
    fn asymmetry_saturates_at_the_two_levels() {
        // A large slow sine drives w to (beta + gamma +- delta)^(-1/mu) at the top and bottom.
        let tf = TransferFunction::new(&[1.0], &[1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.5, 2.0, 0.0).unwrap();
        let terms = TermValues {
            asymmetry: 0.6,
            ..TermValues::default()
        };
        let (amp, om) = (30.0, 1.0);
        let n = 2000;
        let dt = 4.0 * std::f64::consts::PI / om / n as f64;
        let sim = simulate_with_terms(&tf, &bw, &terms, sine(amp, om), dt, n, 4).unwrap();
        let top = sim.w.iter().cloned().fold(f64::MIN, f64::max);
        let bottom = sim.w.iter().cloned().fold(f64::MAX, f64::min);
        assert_relative_eq!(top, (1.5f64 + 0.6).powf(-0.5), max_relative = 1e-6);
        assert_relative_eq!(bottom, -(1.5f64 - 0.6).powf(-0.5), max_relative = 1e-6);
    }

    #[test]
    fn stiffness_degradation_keeps_the_level_and_pinching_slips_past_zero() {
        // A slow large sine through a static gain: eta leaves the saturation level, and pinching
        // takes (1 - zeta1) of the slope dw/dx at the band's centre on the loading branch.
        let tf = TransferFunction::new(&[1.0], &[1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.5, 2.0, 0.0).unwrap();
        let (amp, om, n) = (30.0, 1.0, 4000);
        let dt = 4.0 * std::f64::consts::PI / om / n as f64;
        let run =
            |t: TermValues| simulate_with_terms(&tf, &bw, &t, sine(amp, om), dt, n, 4).unwrap();
        let d = TermValues::default();
        let soft = run(TermValues {
            stiffness_degradation: 0.05,
            ..d
        });
        let top = soft.w.iter().cloned().fold(f64::MIN, f64::max);
        assert_relative_eq!(top, 1.5f64.powf(-0.5), max_relative = 1e-4);
        let pinched = run(TermValues { pinching: 0.6, ..d });
        let plain = run(TermValues {
            sensor_lag: 1e-300,
            ..d
        });
        // Slope dw/dx where w crosses the band's centre going down (second half of the first period).
        let slope = |s: &TermSimulation, level: f64| {
            let k = (n / 2..n - 1)
                .find(|&k| s.w[k] >= level && s.w[k + 1] < level)
                .unwrap();
            (s.w[k + 1] - s.w[k]) / (s.x[k + 1] - s.x[k])
        };
        let centre = -PINCHING_CENTRE * 1.5f64.powf(-0.5);
        let ratio = slope(&pinched, centre) / slope(&plain, centre);
        assert!((ratio - 0.4).abs() < 0.02, "{ratio}");
    }

    #[test]
    fn validation() {
        let (tf, bw) = plant();
        let bad = |t: TermValues, text: &str, nonfinite: bool| {
            let e = simulate_with_terms(&tf, &bw, &t, sine(1.0, 1.0), 0.1, 10, 1).unwrap_err();
            if nonfinite {
                assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
            } else {
                assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
            }
            assert!(e.to_string().contains(text), "{e}");
        };
        let d = TermValues::default();
        bad(
            TermValues {
                sensor_lag: -1.0,
                ..d
            },
            TermKind::SensorLag.name(),
            false,
        );
        bad(TermValues { play: -0.1, ..d }, TermKind::Play.name(), false);
        bad(
            TermValues {
                stiffness_degradation: -0.1,
                ..d
            },
            TermKind::StiffnessDegradation.name(),
            false,
        );
        bad(
            TermValues { pinching: 1.0, ..d },
            TermKind::Pinching.name(),
            false,
        );
        bad(
            TermValues {
                coulomb_smoothing: 0.0,
                ..d
            },
            COULOMB_SMOOTHING_KEY,
            false,
        );
        bad(
            TermValues {
                coulomb_smoothing: 0.6,
                ..d
            },
            COULOMB_SMOOTHING_KEY,
            false,
        );
        bad(
            TermValues {
                asymmetry: -1.5,
                ..d
            },
            "beta + gamma",
            false,
        );
        bad(
            TermValues {
                viscous: f64::NAN,
                ..d
            },
            TermKind::Viscous.name(),
            true,
        );
        let (offset, play) = (TermKind::Offset.name(), TermKind::Play.name());
        let e = TermValues::from_named([(offset, 1.0), ("spring", 2.0)]).unwrap_err();
        assert!(e.to_string().contains("\"spring\""), "{e}");
        let e = TermValues::from_named([(TermKind::Distortion.name(), 0.1)]).unwrap_err();
        assert!(e.to_string().contains("no time-domain form"), "{e}");
        let t = TermValues::from_named([(play, 0.2), (COULOMB_SMOOTHING_KEY, 0.05)]).unwrap();
        assert_eq!((t.play, t.coulomb_smoothing, t.offset), (0.2, 0.05, 0.0));
    }
}

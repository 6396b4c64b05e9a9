//! The mechanical terms across the hysteretic element, on its own input `x = G u` (design.md 9.1,
//! place x; 9.4): `k_x x + c_x xdot + m_x xddot + f_x tanh(xdot / (eps_x Vx))`, added to the
//! output beside `w` (before the sensor lag and the offset, as the terms on u).
//!
//! x and its derivatives come from the linear part's state, exactly: with the controllable
//! canonical realisation `xsdot = A xs + B v`, `x = C xs + D v` (`v(t) = u(t - delay)`),
//!
//! ```text
//! xdot  = C xsdot + D vdot,                  xsdot  = A xs + B v,
//! xddot = C xsddot + D vddot,                xsddot = A xsdot + B vdot,
//! ```
//!
//! so [`Companion::state_derivative`] applied twice gives both. Where G's relative degree r is
//! low the input's own derivatives enter: `xdot` holds `D vdot` when r = 0; `xddot` holds
//! `C B vdot` when r = 1 and `D vddot` when r = 0 (for r >= 2, `D = C B = 0` and both are
//! functions of the state alone). Those derivatives are the ones the terms on u use: analytic for
//! a sine, the Catmull-Rom interpolant's slope and right-hand second derivative for samples (it
//! jumps at the knots, as for `inertia` on u); never a difference quotient of x. An input
//! derivative beyond the second is never needed (inertia, the highest term, needs `vddot` at
//! r = 0), so no G is refused; what x cannot carry is the impulse of a step in `v`: the delayed
//! input starts at `t = delay` from 0 to `u(0)`, and with r = 0 (r <= 1 for inertia) the true
//! `xdot` (`xddot`) holds a Dirac there, which the samples do not show (as the plain integrator's
//! `wdot` does not).
//!
//! The friction's velocity scale `Vx` is the peak of `|xdot|`: for a sine the steady one,
//! `|U| |G(j omega)| omega` (the steady-loop model's `|A| omega`, so a long run's last period is
//! the periodic model's); for samples the largest `|xdot|` at the output samples of the run
//! (one pass of the linear part alone before the run). `Vx = 0` makes the friction term 0.

use super::rk4::{axpy, Scratch, Steps};
use crate::error::{finite, CoreError, Result};
use crate::linear::Companion;
use crate::terms::{Place, TermKind, COULOMB_SMOOTHING, COULOMB_SMOOTHING_MAX};

/// Parameters of the mechanical terms on x (0: absent, which is also what 0 means physically).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnXValues {
    /// Stiffness `k_x` (`[y]/[x]`).
    pub stiffness: f64,
    /// Viscous damping `c_x` (`[y] s/[x]`).
    pub viscous: f64,
    /// Inertia `m_x` (`[y] s^2/[x]`).
    pub inertia: f64,
    /// Dry friction level `f_x` (`[y]`).
    pub coulomb: f64,
    /// `eps_x` of `tanh(xdot / (eps_x Vx))`, in `(0, 0.5]`.
    pub coulomb_smoothing: f64,
}

impl Default for OnXValues {
    fn default() -> Self {
        Self {
            stiffness: 0.0,
            viscous: 0.0,
            inertia: 0.0,
            coulomb: 0.0,
            coulomb_smoothing: COULOMB_SMOOTHING,
        }
    }
}

/// The name of `kind` acting on x, `"<code name>@<tag>"` (composed, never spelled).
pub fn placed_name(kind: TermKind) -> String {
    format!("{}@{}", kind.name(), Place::X.tag())
}

/// The key of the on-x friction's smoothing in a simulation's `{name: value}` map: the placed
/// name with the suffix of [`crate::terms::COULOMB_SMOOTHING_KEY`] (`"<coulomb>@x_smoothing"`).
pub fn smoothing_key() -> String {
    format!("{}{}", placed_name(TermKind::Coulomb), SMOOTHING_SUFFIX)
}

/// What follows a term's name in the key of its smoothing setting.
const SMOOTHING_SUFFIX: &str = "_smoothing";

impl OnXValues {
    /// Where `kind`'s value on x is kept, `None` for a term that cannot act on x.
    pub fn slot(&mut self, kind: TermKind) -> Option<&mut f64> {
        match kind {
            TermKind::Stiffness => Some(&mut self.stiffness),
            TermKind::Viscous => Some(&mut self.viscous),
            TermKind::Inertia => Some(&mut self.inertia),
            TermKind::Coulomb => Some(&mut self.coulomb),
            _ => None,
        }
    }

    /// Whether any term on x is present (non-zero).
    pub fn is_active(&self) -> bool {
        self.stiffness != 0.0 || self.viscous != 0.0 || self.inertia != 0.0 || self.coulomb != 0.0
    }

    /// All finite, `0 < eps_x <= 0.5`.
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`] naming the placed term.
    pub fn validate(&self) -> Result<()> {
        for (kind, v) in [
            (TermKind::Stiffness, self.stiffness),
            (TermKind::Viscous, self.viscous),
            (TermKind::Inertia, self.inertia),
            (TermKind::Coulomb, self.coulomb),
        ] {
            finite(&placed_name(kind), v)?;
        }
        let key = smoothing_key();
        let eps = finite(&key, self.coulomb_smoothing)?;
        if !(eps > 0.0 && eps <= COULOMB_SMOOTHING_MAX) {
            return Err(CoreError::InvalidParameter(format!(
                "{key} eps = {eps} must be in (0, {COULOMB_SMOOTHING_MAX}]"
            )));
        }
        Ok(())
    }
}

/// `(x, xdot, xddot)` of the linear part from its state (module header), with scratch space.
pub(super) struct Kinematics<'a> {
    comp: &'a Companion,
    xsdot: Vec<f64>,
    xsddot: Vec<f64>,
}

impl<'a> Kinematics<'a> {
    pub(super) fn new(comp: &'a Companion) -> Self {
        let n = comp.order();
        Self {
            comp,
            xsdot: vec![0.0; n],
            xsddot: vec![0.0; n],
        }
    }

    /// At state `xs` and delayed input `(v, vdot, vddot)`.
    pub(super) fn at(&mut self, xs: &[f64], (v, vdot, vddot): (f64, f64, f64)) -> (f64, f64, f64) {
        let comp = self.comp;
        let x = comp.output_row(xs) + comp.d * v;
        comp.state_derivative(xs, v, &mut self.xsdot);
        let xdot = comp.output_row(&self.xsdot) + comp.d * vdot;
        comp.state_derivative(&self.xsdot, vdot, &mut self.xsddot);
        let xddot = comp.output_row(&self.xsddot) + comp.d * vddot;
        (x, xdot, xddot)
    }
}

/// The terms on x with their velocity scale: their value from the linear part's state.
pub(super) struct OnX<'a> {
    values: OnXValues,
    /// `eps_x Vx`; 0 when x never moves (then the friction term is 0).
    velocity_scale: f64,
    kin: Kinematics<'a>,
}

impl<'a> OnX<'a> {
    /// `peak_rate` is `Vx` (module header).
    pub(super) fn new(values: OnXValues, comp: &'a Companion, peak_rate: f64) -> Self {
        Self {
            values,
            velocity_scale: values.coulomb_smoothing * peak_rate,
            kin: Kinematics::new(comp),
        }
    }

    /// `k_x x + c_x xdot + m_x xddot + f_x tanh(xdot / (eps_x Vx))` at state `xs` and delayed
    /// input `(v, vdot, vddot)` (units of y).
    pub(super) fn at(&mut self, xs: &[f64], input: (f64, f64, f64)) -> f64 {
        let (x, xdot, xddot) = self.kin.at(xs, input);
        let p = &self.values;
        let friction = if self.velocity_scale > 0.0 {
            p.coulomb * (xdot / self.velocity_scale).tanh()
        } else {
            0.0
        };
        p.stiffness * x + p.viscous * xdot + p.inertia * xddot + friction
    }
}

/// Steps the linear part alone from rest over the output grid `t_k = k dt` with the integrators'
/// RK4 (`substeps` steps per sample, the same operations in the same order, so its states are
/// theirs to the bit: x does not depend on w) and calls `visit(k, t_k, xs(t_k))` at every sample.
/// `input(t)` is the delayed input `(v, vdot, vddot)`.
pub(super) fn linear_pass(
    comp: &Companion,
    input: impl Fn(f64) -> (f64, f64, f64),
    dt: f64,
    n_samples: usize,
    substeps: usize,
    mut visit: impl FnMut(usize, f64, &[f64]),
) {
    let Steps { h, half_h, h_sixth } = Steps::new(dt, substeps);
    let mut xs = vec![0.0; comp.order()];
    let mut sc = Scratch::new(comp.order());
    let stage = |xs: &[f64], t: f64, out: &mut [f64]| comp.state_derivative(xs, input(t).0, out);
    for k in 0..n_samples {
        let t = k as f64 * dt;
        visit(k, t, &xs);
        if k + 1 == n_samples {
            break;
        }
        for s in 0..substeps {
            let ts = t + s as f64 * h;
            stage(&xs, ts, &mut sc.k1);
            axpy(&mut sc.tmp, &xs, half_h, &sc.k1);
            stage(&sc.tmp, ts + half_h, &mut sc.k2);
            axpy(&mut sc.tmp, &xs, half_h, &sc.k2);
            stage(&sc.tmp, ts + half_h, &mut sc.k3);
            axpy(&mut sc.tmp, &xs, h, &sc.k3);
            stage(&sc.tmp, ts + h, &mut sc.k4);
            sc.advance(&mut xs, h_sixth);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear::TransferFunction;
    use approx::assert_relative_eq;

    #[test]
    fn kinematics_follow_the_transfer_function_at_every_relative_degree() {
        // A sine through G from a state on its steady orbit: x, xdot, xddot are Re of
        // (1, j w, -w^2) G(j w) U e^{j w t}. The state is set from the steady solution
        // xs = Re[(j w I - A)^-1 B U e^{j w t}], which for the companion form is
        // xs_i = Re[(j w)^(n-1-i) / den(j w)] U e^{j w t} times den's leading coefficient.
        let om = 1.7;
        for (num, den) in [
            (vec![2.0], vec![0.5, 0.3, 1.0]),           // r = 2
            (vec![1.0, 0.4], vec![0.5, 0.3, 1.0]),      // r = 1
            (vec![0.7, 1.0, 0.4], vec![0.5, 0.3, 1.0]), // r = 0
            (vec![1.5], vec![1.0]),                     // static gain
        ] {
            let tf = TransferFunction::new(&num, &den, 0.0).unwrap();
            let comp = tf.realize();
            let n = comp.order();
            let jw = nalgebra::Complex::new(0.0, om);
            let poly = |p: &[f64]| {
                p.iter()
                    .fold(nalgebra::Complex::new(0.0, 0.0), |a, &c| a * jw + c)
            };
            let dn = poly(&den) / den[0];
            let t = 0.37;
            let e = nalgebra::Complex::from_polar(1.0, om * t);
            let xs: Vec<f64> = (0..n)
                .map(|i| (jw.powi((n - 1 - i) as i32) / dn * e).re)
                .collect();
            let (v, vdot, vddot) = (e.re, (jw * e).re, (jw * jw * e).re);
            let g = poly(&num) / poly(&den);
            let mut kin = Kinematics::new(&comp);
            let (x, xdot, xddot) = kin.at(&xs, (v, vdot, vddot));
            assert_relative_eq!(x, (g * e).re, epsilon = 1e-12);
            assert_relative_eq!(xdot, (g * jw * e).re, epsilon = 1e-12);
            assert_relative_eq!(xddot, (g * jw * jw * e).re, epsilon = 1e-12);
        }
    }

    #[test]
    fn validation_names_the_placed_term() {
        let d = OnXValues::default();
        assert!(!d.is_active());
        let e = OnXValues {
            viscous: f64::NAN,
            ..d
        }
        .validate()
        .unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        assert!(
            e.to_string().contains(&placed_name(TermKind::Viscous)),
            "{e}"
        );
        let e = OnXValues {
            coulomb_smoothing: 0.0,
            ..d
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains(&smoothing_key()), "{e}");
        assert_eq!(
            smoothing_key(),
            format!("{}@{}_smoothing", TermKind::Coulomb.name(), Place::X.tag())
        );
        let mut v = d;
        *v.slot(TermKind::Inertia).unwrap() = 0.5;
        assert!(v.is_active() && v.inertia == 0.5);
        assert!(v.slot(TermKind::Play).is_none());
    }
}

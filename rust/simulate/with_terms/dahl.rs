//! Dahl friction's time-domain form (`rust/dahl.rs` has its steady loop): the friction force `F`
//! is one more state, `F' = sigma v' (1 - sgn(v') F / Fc)`, `F(0) = 0`, along the measured input
//! (`v = u`) or across the hysteretic element (`v = x`). `F` adds to the output and does not feed
//! back, so it rides along the RK4 step with the rates `v'` of its four stages. `Fc = 0` or
//! `sigma = 0` is no friction (`F = 0`, as the steady loop's limit).

/// Dahl friction at one place: level `fc` ([y]) and pre-sliding stiffness `sigma`.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Dahl {
    pub(super) fc: f64,
    pub(super) sigma: f64,
}

impl Dahl {
    /// Whether the friction moves at all (`Fc > 0` and `sigma > 0`).
    pub(super) fn is_active(&self) -> bool {
        self.fc > 0.0 && self.sigma > 0.0
    }

    /// `F' = sigma vdot (1 - sgn(vdot) F / Fc)`; 0 when inactive.
    #[inline]
    pub(super) fn rate(&self, vdot: f64, f: f64) -> f64 {
        if !self.is_active() {
            return 0.0;
        }
        let s = if vdot > 0.0 {
            1.0
        } else if vdot < 0.0 {
            -1.0
        } else {
            0.0
        };
        self.sigma * vdot * (1.0 - s * f / self.fc)
    }

    /// One RK4 step of `F` over `h` with the stage rates `vdot = (v1, vm2, vm3, v4)`: the new `F`
    /// and its third-order continuous extension at the step's middle.
    #[inline]
    pub(super) fn step(&self, f: f64, h: f64, vdot: [f64; 4]) -> (f64, f64) {
        let half_h = 0.5 * h;
        let k1 = self.rate(vdot[0], f);
        let k2 = self.rate(vdot[1], f + half_h * k1);
        let k3 = self.rate(vdot[2], f + half_h * k2);
        let k4 = self.rate(vdot[3], f + h * k3);
        (
            f + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4),
            f + h * (5.0 * k1 + 4.0 * (k2 + k3) - k4) / 24.0,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::on_x::placed_name;
    use super::super::super::Input;
    use super::super::{simulate_with_terms, TermValues};
    use crate::bouc_wen::BoucWen;
    use crate::linear::TransferFunction;
    use crate::terms::TermKind;

    fn sine(amplitude: f64, omega: f64) -> Input<'static> {
        Input::Sine { amplitude, omega }
    }

    /// The last period of a long simulation with Dahl friction alone, `y - w` (the friction force), on
    /// a grid of `p` samples per period of `u = amp cos(om t)`.
    fn dahl_force(
        tf: &TransferFunction,
        terms: &TermValues,
        amp: f64,
        om: f64,
        p: usize,
    ) -> Vec<f64> {
        let bw = BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap();
        let periods = 12;
        let dt = 2.0 * std::f64::consts::PI / om / p as f64;
        let n = periods * p + 1;
        let s = simulate_with_terms(tf, &bw, terms, sine(amp, om), dt, n, 8).unwrap();
        (0..p)
            .map(|j| s.y[(periods - 1) * p + j] - s.w[(periods - 1) * p + j])
            .collect()
    }

    #[test]
    fn dahl_steady_state_is_the_closed_form_loop() {
        // On u: F follows u = U cos(theta), theta = 2 pi j / P at the period's start; on x, x = U |G|
        // cos(theta + arg G) through a resonant G with a delay (freq_response carries it). The closed
        // form is rust/dahl.rs's, made without a time loop.
        let (amp, om, p) = (1.3, 2.0, 64);
        let first = TransferFunction::new(&[1.0], &[0.2, 1.0], 0.0).unwrap();
        let on_u = TermValues {
            dahl: 0.4,
            dahl_sigma: 1.5,
            ..TermValues::default()
        };
        let f = dahl_force(&first, &on_u, amp, om, p);
        let l = crate::dahl::dahl_loop(amp, 0.0, 0.4, 1.5, p).unwrap();
        let err = f
            .iter()
            .zip(&l.f)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-6 * 0.4, "on u: {err}");
        let resonant = TransferFunction::new(&[1.0], &[0.05, 0.1, 1.0], 0.07).unwrap();
        let on_x = TermValues {
            dahl_x: 0.3,
            dahl_sigma_x: 4.0,
            ..TermValues::default()
        };
        let f = dahl_force(&resonant, &on_x, amp, om, p);
        let (re, im) = resonant.freq_response(om);
        let l = crate::dahl::dahl_loop(amp * re.hypot(im), im.atan2(re), 0.3, 4.0, p).unwrap();
        let err = f
            .iter()
            .zip(&l.f)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // r = sigma a / Fc = 21 here: the relaxation rate sigma |xdot| / Fc times the step is 0.25, and
        // RK4 errs by 4.4e-5 Fc (measured; on u, r = 4.9, within 1e-6 Fc).
        assert!(err < 1e-4 * 0.3, "on x: {err}");
        // Either parameter 0 is no friction at all: the run is the plain one.
        let off = TermValues {
            dahl: 0.4,
            ..TermValues::default()
        };
        assert!(dahl_force(&first, &off, amp, om, p)
            .iter()
            .all(|v| *v == 0.0));
    }

    #[test]
    fn dahl_values_by_name_and_bad_ones_by_name() {
        let on_x = placed_name(TermKind::Dahl);
        let named = [
            (TermKind::Dahl.name(), 0.2),
            (TermKind::DahlSigma.name(), 3.0),
            (on_x.as_str(), 0.1),
        ];
        let t = TermValues::from_named(named).unwrap();
        assert_eq!(
            (t.dahl, t.dahl_sigma, t.dahl_x, t.dahl_sigma_x),
            (0.2, 3.0, 0.1, 0.0)
        );
        assert!(
            t.describe().contains(&format!("{on_x} = 1e-1")),
            "{}",
            t.describe()
        );
        let tf = TransferFunction::new(&[1.0], &[0.2, 1.0], 0.05).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap();
        let bad = TermValues {
            dahl_sigma_x: -1.0,
            ..TermValues::default()
        };
        let e = simulate_with_terms(&tf, &bw, &bad, sine(1.0, 2.0), 0.05, 10, 2).unwrap_err();
        assert!(e.to_string().contains(">= 0"), "{e}");
    }
}

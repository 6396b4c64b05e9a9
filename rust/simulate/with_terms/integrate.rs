//! The RK4 loop of the augmented model with its play, lag and energy states (module header of
//! `with_terms.rs`).

use super::super::on_x::OnX;
use super::super::rk4::{axpy, Scratch, Steps};
use super::dahl::Dahl;
use super::derivatives::Derivatives;
use super::lag::lag_weights;
use super::rhs::{Augmented, Mode};
use super::{TermSimulation, TermValues};

/// Relative slack of the play's engagement test `|x - xp| >= b`: after a clamp `x - xp` equals `b`
/// only to the rounding of `x`.
const PLAY_ENGAGE_RTOL: f64 = 1e-12;

impl<S: Derivatives> Augmented<'_, S> {
    pub(super) fn integrate(
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
        let Steps { h, half_h, h_sixth } = Steps::new(dt, substeps);
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
        // Dahl friction's forces on u and on x (with_terms/dahl.rs); added only when active, so
        // that the other terms' runs round exactly as before.
        let dahl_u = Dahl {
            fc: terms.dahl,
            sigma: terms.dahl_sigma,
        };
        let dahl_x = Dahl {
            fc: terms.dahl_x,
            sigma: terms.dahl_sigma_x,
        };
        let has_dahl = terms.dahl_active();
        let (mut fu, mut fx) = (0.0f64, 0.0f64);
        let with_dahl = |f: f64, fu: f64, fx: f64| if has_dahl { f + (fu + fx) } else { f };
        let mut sc = Scratch::new(n);
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
                    with_dahl(self.forcing(w, t, &xs, on_x), fu, fx)
                };
            if k == last {
                break;
            }
            for s in 0..substeps {
                let ts = t + s as f64 * h;
                let (tm, te) = (ts + half_h, ts + h);
                let (in1, inm, in4) = (self.delayed(ts), self.delayed(tm), self.delayed(te));

                let xdot1 = self.linear(&xs, in1, &mut sc.k1);
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
                axpy(&mut sc.tmp, &xs, half_h, &sc.k1);
                let xdot2 = self.linear(&sc.tmp, inm, &mut sc.k2);
                let p2 = played(xdot2);
                let d2 = element(p2, w2);
                let kw2 = self.rate(d2, w2, e2);
                let ke2 = w2 * d2;
                let (w3, e3) = (w + half_h * kw2, en + half_h * ke2);
                axpy(&mut sc.tmp, &xs, half_h, &sc.k2);
                let xdot3 = self.linear(&sc.tmp, inm, &mut sc.k3);
                let p3 = played(xdot3);
                let d3 = element(p3, w3);
                let kw3 = self.rate(d3, w3, e3);
                let ke3 = w3 * d3;
                let (w4, e4) = (w + h * kw3, en + h * ke3);
                axpy(&mut sc.tmp, &xs, h, &sc.k3);
                let xdot4 = self.linear(&sc.tmp, in4, &mut sc.k4);
                let p4 = played(xdot4);
                let d4 = element(p4, w4);
                let kw4 = self.rate(d4, w4, e4);
                let ke4 = w4 * d4;

                // Third-order continuous extension of the RK4 step at its midpoint.
                let w_mid = w + h * (5.0 * kw1 + 4.0 * (kw2 + kw3) - kw4) / 24.0;
                let f0 = if has_lag {
                    if on_x.is_some() {
                        sc.middle(&xs, h, &mut xs_mid);
                    }
                    with_dahl(self.forcing(w, ts, &xs, on_x), fu, fx)
                } else {
                    0.0
                };
                sc.advance(&mut xs, h_sixth);
                w += h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4);
                let (mut fu_mid, mut fx_mid) = (fu, fx);
                if has_dahl {
                    // The undelayed input's rate on u (as the output terms'), x's on x.
                    let udot = |t: f64| self.src.at(t).1;
                    let um = udot(tm);
                    (fu, fu_mid) = dahl_u.step(fu, h, [udot(ts), um, um, udot(te)]);
                    (fx, fx_mid) = dahl_x.step(fx, h, [xdot1, xdot2, xdot3, xdot4]);
                }
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
                    let fm = with_dahl(self.forcing(w_mid, tm, &xs_mid, on_x), fu_mid, fx_mid);
                    let f1 = with_dahl(self.forcing(w, te, &xs, on_x), fu, fx);
                    ys = decay * ys + (l0 * f0 + lm * fm + l1 * f1);
                }
            }
        }
    }
}

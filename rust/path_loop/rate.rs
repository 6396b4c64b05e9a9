//! The rate `h(w, s) = 1 - |w|^mu (gamma + (beta s + delta) sgn w)` of the path loop (times
//! Foliente's pinching factor when asked), with the pieces of its derivatives that the RK4 step's
//! sensitivities need: one `ln` and one `exp` per stage.

use crate::bouc_wen::sgn;
use crate::terms::{PINCHING_CENTRE, PINCHING_WIDTH};

/// Shape parameters of `h(w, s)`.
#[derive(Clone, Copy)]
pub(super) struct Shape {
    pub(super) beta: f64,
    pub(super) gamma: f64,
    pub(super) mu: f64,
    pub(super) delta: f64,
    /// Pinching `zeta1`, and whether its factor (and `d/dzeta1`) is computed at all.
    pub(super) pinch: f64,
    pub(super) pinched: bool,
    /// `w_u = (beta + gamma)^(-1/mu)`, the virgin saturation level the pinching band scales with.
    pub(super) w_u: f64,
    /// `d w_u / d(beta, gamma, mu)`.
    pub(super) dwu: [f64; 3],
}

impl Shape {
    pub(super) fn new(beta: f64, gamma: f64, mu: f64, delta: f64, pinch: Option<f64>) -> Self {
        let bg = beta + gamma;
        let w_u = bg.powf(-1.0 / mu);
        let d_bg = -w_u / (mu * bg);
        Self {
            beta,
            gamma,
            mu,
            delta,
            pinch: pinch.unwrap_or(0.0),
            pinched: pinch.is_some(),
            w_u,
            dwu: [d_bg, d_bg, w_u * bg.ln() / (mu * mu)],
        }
    }
}

/// `h(w, s)` and the pieces of its derivatives at one RK4 stage: one `ln` and one `exp`.
#[derive(Clone, Copy)]
pub(super) struct Rate {
    /// `h = 1 - |w|^mu c`.
    pub(super) h: f64,
    /// `dh/dw = -mu |w|^(mu-1) (gamma sgn w + beta s + delta)`.
    pub(super) hw: f64,
    /// `|w|^mu`.
    pub(super) wmu: f64,
    /// `ln |w|` (0 at w = 0, where it is multiplied by `|w|^mu = 0`).
    pub(super) lnw: f64,
    /// `sgn(w)`.
    pub(super) sw: f64,
    /// `c = gamma + (beta s + delta) sgn(w)`.
    pub(super) c: f64,
    /// The pinching factor `P = 1 - zeta1 G` (1 without pinching; `h` above includes it).
    pub(super) pf: f64,
    /// `h / P`, the Bouc-Wen part of `h`.
    pub(super) hb: f64,
    /// `dP/dw_u` and `dP/dzeta1 = -G` (0 without pinching).
    pub(super) p_wu: f64,
    pub(super) p_z: f64,
}

#[inline(always)]
pub(super) fn rate(p: &Shape, s: f64, w: f64) -> Rate {
    let aw = w.abs();
    let sw = sgn(w);
    let (wmu, wmu1, lnw) = if aw > 0.0 {
        let lnw = aw.ln();
        let wmu = (p.mu * lnw).exp();
        (wmu, wmu / aw, lnw)
    } else {
        (0.0, 0.0, 0.0)
    };
    let c = p.gamma + (p.beta * s + p.delta) * sw;
    let hb = 1.0 - wmu * c;
    // d/dw |w|^mu = mu |w|^(mu-1) sgn(w); d/dw sgn(w)|w|^mu = mu |w|^(mu-1).
    let hbw = -p.mu * wmu1 * (p.gamma * sw + p.beta * s + p.delta);
    if !p.pinched {
        return Rate {
            h: hb,
            hw: hbw,
            wmu,
            lnw,
            sw,
            c,
            pf: 1.0,
            hb,
            p_wu: 0.0,
            p_z: 0.0,
        };
    }
    // Foliente's P = 1 - zeta1 exp(-z^2), z = (w s / w_u - q) / zeta2.
    let width = PINCHING_WIDTH * p.w_u;
    let z = (w * s - PINCHING_CENTRE * p.w_u) / width;
    let g = (-z * z).exp();
    let pf = 1.0 - p.pinch * g;
    // dP/dz = 2 zeta1 G z; dz/dw = s / width; dz/dw_u = -(w s) / (w_u width).
    let p_dz = 2.0 * p.pinch * g * z;
    Rate {
        h: hb * pf,
        hw: hbw * pf + hb * p_dz * s / width,
        wmu,
        lnw,
        sw,
        c,
        pf,
        hb,
        p_wu: -p_dz * w * s / (p.w_u * width),
        p_z: -g,
    }
}

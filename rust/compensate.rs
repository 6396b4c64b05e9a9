//! Feedforward compensation kernels (issue 21, item 1): the Bouc-Wen operator inverted along a
//! sampled path, and the actuator's rate limiter. NumPy oracle: `bouc_wen_id.reference.compensate`.
//!
//! The Bouc-Wen rate has the multiplicative structure `wdot = xdot h(w, sgn xdot)` with
//! `h = alpha - |w|^mu (beta sgn(xdot w) + gamma + delta sgn w)` (`delta` the asymmetry), and
//! `h > 0` on the open range `-w_sat- < w < w_sat+`. There the operator is invertible: over a sample
//! interval where `w` moves monotonically from `w_a` to `w_b`, `x` moves by
//! `int_{w_a}^{w_b} dw / h(w, sgn(w_b - w_a))`, exactly (the element is rate-independent). The
//! integral is an 8-node Gauss-Legendre rule, split at `w = 0`, on [`FINE_PANELS`] panels where
//! `1/h` varies by more than [`FINE_RATIO`] over the interval.

use crate::error::{CoreError, Result};

/// Gauss-Legendre nodes on `[0, 1]` (8 nodes), ascending: numpy's `leggauss(8)` mapped, to the digit.
pub const GL_NODES: [f64; 8] = [
    0.019855071751231912,
    0.10166676129318664,
    0.2372337950418355,
    0.4082826787521751,
    0.5917173212478248,
    0.7627662049581645,
    0.8983332387068134,
    0.9801449282487681,
];
/// Their weights on `[0, 1]`.
pub const GL_WEIGHTS: [f64; 8] = [
    0.05061426814518853,
    0.11119051722668721,
    0.15685332293894344,
    0.18134189168918083,
    0.18134189168918083,
    0.15685332293894344,
    0.11119051722668721,
    0.05061426814518853,
];
/// Panels of the rule on intervals where `1/h` varies by more than [`FINE_RATIO`].
pub const FINE_PANELS: usize = 16;
/// The variation of `h` over an interval beyond which it is split into panels.
pub const FINE_RATIO: f64 = 1.2;

/// The Bouc-Wen element with its asymmetry, as the inverse sees it.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    pub mu: f64,
    pub delta: f64,
    pub w0: f64,
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl Element {
    /// `h(w, s) = alpha - |w|^mu (beta s sgn w + gamma + delta sgn w)`.
    pub fn h(&self, w: f64, s: f64) -> f64 {
        let sw = sign(w);
        self.alpha - w.abs().powf(self.mu) * (self.beta * s * sw + self.gamma + self.delta * sw)
    }

    /// `(w_sat-, w_sat+)`: `(alpha / (beta + gamma -+ delta))^(1/mu)`.
    pub fn saturation(&self) -> (f64, f64) {
        let down = (self.alpha / (self.beta + self.gamma - self.delta)).powf(1.0 / self.mu);
        let up = (self.alpha / (self.beta + self.gamma + self.delta)).powf(1.0 / self.mu);
        (down, up)
    }

    /// `int_a^b dw / h(w, s)` (`a`, `b` on one side of 0).
    fn integral(&self, a: f64, b: f64, s: f64) -> f64 {
        let span = b - a;
        let rule = |lo: f64, width: f64| -> f64 {
            let mut acc = 0.0;
            for (x, wt) in GL_NODES.iter().zip(GL_WEIGHTS.iter()) {
                acc += wt / self.h(lo + width * x, s);
            }
            width * acc
        };
        let (ha, hb) = (self.h(a, s), self.h(b, s));
        if ha.max(hb) > FINE_RATIO * ha.min(hb) {
            let width = span / FINE_PANELS as f64;
            (0..FINE_PANELS)
                .map(|p| rule(a + span * (p as f64 / FINE_PANELS as f64), width))
                .sum()
        } else {
            rule(a, span)
        }
    }
}

/// The path `x` whose Bouc-Wen output is `w` at the samples, from the state `(x0, element.w0)`.
///
/// Errors: a non-finite sample ([`CoreError::NonFinite`]); a sample at or beyond the saturation
/// levels, or an inadmissible element ([`CoreError::InvalidParameter`]).
pub fn invert_path(w: &[f64], element: &Element, x0: f64) -> Result<Vec<f64>> {
    let e = element;
    if !(e.alpha > 0.0
        && e.mu >= 1.0
        && e.beta + e.gamma - e.delta.abs() > 0.0
        && e.beta >= e.gamma)
    {
        return Err(CoreError::InvalidParameter(format!(
            "the element (alpha {}, beta {}, gamma {}, mu {}, delta {}) has no invertible range",
            e.alpha, e.beta, e.gamma, e.mu, e.delta
        )));
    }
    let (down, up) = e.saturation();
    let mut out = Vec::with_capacity(w.len());
    let (mut prev, mut x) = (e.w0, x0);
    for (k, &wk) in w.iter().enumerate() {
        if !wk.is_finite() {
            return Err(CoreError::NonFinite(format!("w[{k}] = {wk}")));
        }
        if wk >= up || wk <= -down || prev >= up || prev <= -down {
            return Err(CoreError::InvalidParameter(format!(
                "w[{k}] = {wk} is outside the invertible range ({}, {up})",
                -down
            )));
        }
        let s = sign(wk - prev);
        if prev * wk < 0.0 {
            x += e.integral(prev, 0.0, s) + e.integral(0.0, wk, s);
        } else {
            x += e.integral(prev, wk, s);
        }
        out.push(x);
        prev = wk;
    }
    Ok(out)
}

/// The command moved toward `target` by at most `step` per sample, from `start`.
pub fn rate_limit(target: &[f64], step: f64, start: f64) -> Result<Vec<f64>> {
    if !(step > 0.0 && step.is_finite()) {
        return Err(CoreError::InvalidParameter(format!(
            "the rate limit's step {step} must be finite and > 0"
        )));
    }
    let mut prev = start;
    Ok(target
        .iter()
        .map(|&t| {
            prev += (t - prev).clamp(-step, step);
            prev
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    const EL: Element = Element {
        alpha: 1.0,
        beta: 0.7,
        gamma: 0.3,
        mu: 1.5,
        delta: 0.2,
        w0: 0.0,
    };

    /// RK4 along `x` with many steps per sample: the forward operator, another way.
    fn forward(x: &[f64], e: &Element) -> Vec<f64> {
        let (mut w, mut prev) = (e.w0, 0.0);
        x.iter()
            .map(|&xk| {
                let sub = 200;
                let h = (xk - prev) / sub as f64;
                let s = sign(h);
                for _ in 0..sub {
                    let k1 = e.h(w, s) * h;
                    let k2 = e.h(w + 0.5 * k1, s) * h;
                    let k3 = e.h(w + 0.5 * k2, s) * h;
                    let k4 = e.h(w + k3, s) * h;
                    w += (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
                }
                prev = xk;
                w
            })
            .collect()
    }

    #[test]
    fn gauss_legendre_rule_is_exact_for_degree_15() {
        let exact = 1.0 / 16.0;
        let rule: f64 = GL_NODES
            .iter()
            .zip(GL_WEIGHTS.iter())
            .map(|(x, w)| w * x.powi(15))
            .sum();
        assert!((rule - exact).abs() < 1e-15);
    }

    #[test]
    fn inverse_composed_with_the_forward_operator_is_the_identity() {
        let (down, up) = EL.saturation();
        let w: Vec<f64> = (0..400)
            .map(|k| {
                let t = k as f64 / 400.0;
                let v = (6.0 * t).sin() * 0.9 + 0.3 * (17.0 * t).cos() - 0.3;
                v.clamp(-0.95 * down, 0.95 * up)
            })
            .collect();
        let x = invert_path(&w, &EL, 0.0).unwrap();
        let back = forward(&x, &EL);
        for (a, b) in w.iter().zip(back.iter()) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }

    #[test]
    fn saturation_and_non_finite_are_refused() {
        let (_, up) = EL.saturation();
        assert!(matches!(
            invert_path(&[0.1, up], &EL, 0.0),
            Err(CoreError::InvalidParameter(_))
        ));
        assert!(matches!(
            invert_path(&[0.1, f64::NAN], &EL, 0.0),
            Err(CoreError::NonFinite(_))
        ));
    }

    #[test]
    fn rate_limit_moves_at_most_one_step() {
        let out = rate_limit(&[1.0, 1.0, -1.0, 0.05], 0.4, 0.0).unwrap();
        let want = [0.4, 0.8, 0.4, 0.05];
        for (a, b) in out.iter().zip(want.iter()) {
            assert!((a - b).abs() < 1e-15);
        }
        assert!(rate_limit(&[1.0], 0.0, 0.0).is_err());
    }
}

//! Dahl friction's steady loop under a sine, in closed form (docs/diagnosis.md, "Dahl friction").
//!
//! Dahl's model (exponent 1): `F' = sigma v' (1 - sgn(v') F / Fc)` along a travel `v` (the
//! measured input u, or the hysteresis' input x), with the friction level `Fc >= 0` and the
//! pre-sliding stiffness `sigma >= 0`. Under `v = a cos(psi)`, `a >= 0`, its periodic steady state
//! is, with `r = sigma a / Fc` and `E = (1 + tanh r) exp(-r xi)`:
//!
//! * on the falling branch (`sin psi >= 0`, from `v = a` down), `xi = (a - v)/a = 1 - cos psi`
//!   and `F = -Fc (1 - E)`;
//! * on the rising branch, `xi = (a + v)/a = 1 + cos psi` and `F = Fc (1 - E)`;
//!
//! so `F = s Fc (1 - E)` with `s = sgn(v')`, and the loop's top is `F_top = Fc tanh r`. No time
//! loop is needed: every column below is the exact derivative of the closed form. `Fc = 0` is no
//! friction (`F = 0`, the column in `Fc` is the sign `s`, the Coulomb limit), `sigma = 0` too
//! (the column in `sigma` is then `v`, the spring limit).
//!
//! Numerics only (no pyo3); the NumPy oracle is `reference/dahl.py`.

use crate::error::{finite, CoreError, Result};

/// The steady Dahl loop on a grid, and its columns.
#[derive(Debug, Clone, Default)]
pub struct DahlLoop {
    /// `F_j` ([y]).
    pub f: Vec<f64>,
    /// `dF_j / dFc`.
    pub d_fc: Vec<f64>,
    /// `dF_j / dsigma`.
    pub d_sigma: Vec<f64>,
    /// `dF_j / da` for the signed amplitude `a` of `v = a cos(theta_j + psi0)`.
    pub d_amplitude: Vec<f64>,
    /// `dF_j / dpsi0`.
    pub d_phase: Vec<f64>,
}

/// The steady loop of Dahl friction driven by `v_j = a cos(2 pi j / p + psi0)` (`a` signed: a
/// negative one is `|a| cos(. + pi)`), with its derivatives in `fc`, `sigma`, `a` and `psi0`.
///
/// Errors: non-finite input, `fc < 0` or `sigma < 0` ([`CoreError::InvalidParameter`]).
pub fn dahl_loop(a: f64, psi0: f64, fc: f64, sigma: f64, p: usize) -> Result<DahlLoop> {
    finite("dahl amplitude", a)?;
    finite("dahl phase", psi0)?;
    finite("dahl Fc", fc)?;
    finite("dahl sigma", sigma)?;
    if fc < 0.0 || sigma < 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "Dahl friction needs Fc >= 0 and sigma >= 0, got Fc = {fc}, sigma = {sigma}"
        )));
    }
    let aa = a.abs();
    let shift = if a < 0.0 { std::f64::consts::PI } else { 0.0 };
    let sa = if a < 0.0 { -1.0 } else { 1.0 };
    // r = sigma |a| / Fc; Fc = 0 is the sharp (Coulomb) limit r = inf.
    let r = if fc > 0.0 {
        sigma * aa / fc
    } else {
        f64::INFINITY
    };
    let th = r.tanh();
    let den = 1.0 + (-2.0 * r).exp();
    let step = 2.0 * std::f64::consts::PI / p as f64;
    let mut out = DahlLoop {
        f: Vec::with_capacity(p),
        d_fc: Vec::with_capacity(p),
        d_sigma: Vec::with_capacity(p),
        d_amplitude: Vec::with_capacity(p),
        d_phase: Vec::with_capacity(p),
    };
    for j in 0..p {
        let psi = (step * j as f64 + psi0 + shift).rem_euclid(2.0 * std::f64::consts::PI);
        let (sn, cs) = psi.sin_cos();
        // Falling from the top over [0, pi], rising over (pi, 2 pi).
        let (s, xi) = if psi <= std::f64::consts::PI {
            (-1.0, 1.0 - cs)
        } else {
            (1.0, 1.0 + cs)
        };
        let em = if r.is_finite() {
            (-r * xi).exp()
        } else if xi > 0.0 {
            0.0
        } else {
            1.0
        };
        let e = 2.0 * em / den;
        // dE/dr = E (1 - tanh r - xi); E' r -> 0 in the sharp limit.
        let de = e * (1.0 - th - xi);
        let de_r = if r.is_finite() { de * r } else { 0.0 };
        out.f.push(s * fc * (1.0 - e));
        out.d_fc.push(s * (1.0 - e) + s * de_r);
        out.d_sigma
            .push(if r.is_finite() { -s * aa * de } else { 0.0 });
        out.d_amplitude.push(if r.is_finite() {
            -s * sigma * de * sa
        } else {
            0.0
        });
        out.d_phase.push(-sigma * aa * e * sn);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of every column, relative tolerance 1e-7.
    #[test]
    fn columns_match_central_differences() {
        for &(a, psi0, fc, sigma) in &[
            (1.3, 0.4, 0.2, 0.5),
            (-0.7, 2.0, 0.05, 3.0),
            (2.0, -1.0, 1.0, 0.1),
        ] {
            let p = 37;
            let l = dahl_loop(a, psi0, fc, sigma, p).unwrap();
            let h = 1e-6;
            let cols: [(&Vec<f64>, [f64; 4]); 4] = [
                (&l.d_amplitude, [h, 0.0, 0.0, 0.0]),
                (&l.d_phase, [0.0, h, 0.0, 0.0]),
                (&l.d_fc, [0.0, 0.0, h, 0.0]),
                (&l.d_sigma, [0.0, 0.0, 0.0, h]),
            ];
            for (col, d) in cols {
                let yp = dahl_loop(a + d[0], psi0 + d[1], fc + d[2], sigma + d[3], p).unwrap();
                let ym = dahl_loop(a - d[0], psi0 - d[1], fc - d[2], sigma - d[3], p).unwrap();
                let scale = col.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
                for (j, c) in col.iter().enumerate() {
                    let fd = (yp.f[j] - ym.f[j]) / (2.0 * h);
                    assert!((fd - c).abs() < 1e-7 * scale, "{j}: {fd} vs {c}");
                }
            }
        }
    }

    #[test]
    fn limits_and_named_errors() {
        // Top of the loop: Fc tanh(sigma a / Fc); Fc = 0 and sigma = 0 give no friction.
        let (a, fc, sigma) = (1.5, 0.3, 0.8);
        let l = dahl_loop(a, 0.0, fc, sigma, 64).unwrap();
        assert!((l.f[0] - fc * (sigma * a / fc).tanh()).abs() < 1e-14);
        assert!((l.f[32] + fc * (sigma * a / fc).tanh()).abs() < 1e-14);
        for (fc, sigma) in [(0.0, 1.0), (1.0, 0.0)] {
            let l = dahl_loop(a, 0.3, fc, sigma, 16).unwrap();
            assert!(l.f.iter().all(|v| *v == 0.0));
        }
        // The sharp limit's Fc column is the sign of the velocity; sigma = 0's sigma column is v.
        let l = dahl_loop(a, 0.3, 0.0, 1.0, 16).unwrap();
        let l0 = dahl_loop(a, 0.3, 1.0, 0.0, 16).unwrap();
        for j in 0..16 {
            let th = 2.0 * std::f64::consts::PI * j as f64 / 16.0 + 0.3;
            assert!((l.d_fc[j] + th.sin().signum()).abs() < 1e-12);
            assert!((l0.d_sigma[j] - a * th.cos()).abs() < 1e-12);
        }
        assert!(dahl_loop(1.0, 0.0, -0.1, 1.0, 8).is_err());
        assert!(dahl_loop(1.0, 0.0, 0.1, -1.0, 8).is_err());
        assert!(dahl_loop(f64::NAN, 0.0, 0.1, 1.0, 8).is_err());
    }
}

//! Estimators on one averaged period `ybar` (`docs/design.md` §3, §4, §6) of the seed paper:
//! the phase estimator (9) `phi = omega tbar` from the first maximum of `ybar`; the spectral
//! derivative `ydot` of `ybar` that feeds the regressor (23); and the gain estimator (27b) at the
//! further frequencies, once `beta`, `gamma`, `mu` are known.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

use crate::error::{all_finite, finite, CoreError, Result};
use crate::solve::{SlsProblem, MIN_SAMPLES};

/// Phase estimator (9): `phi = omega tbar = 2 pi j*/P` (rad, in `[0, 2 pi)`) with `j*` the first
/// maximum of `ybar` (one averaged period, length P >= 4).
///
/// In steady state the Bouc-Wen output peaks with its input `x = U |G| cos(omega t - phi)`, so
/// the time of the maximum gives `phi` modulo the grid step `2 pi/P`.
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::InsufficientData`] (P < 4),
/// [`CoreError::ZeroAmplitude`] (constant `ybar`: no maximum to time the phase by).
pub fn phase_from_max(ybar: &[f64]) -> Result<f64> {
    all_finite("ybar", ybar)?;
    if ybar.len() < MIN_SAMPLES {
        return Err(CoreError::InsufficientData(format!(
            "ybar needs at least {MIN_SAMPLES} samples, got {}",
            ybar.len()
        )));
    }
    let (mut j_max, mut y_max, mut y_min) = (0, ybar[0], ybar[0]);
    for (j, &y) in ybar.iter().enumerate() {
        // Strict: the first of equal maxima wins (numpy.argmax).
        if y > y_max {
            (j_max, y_max) = (j, y);
        }
        y_min = y_min.min(y);
    }
    if y_max == y_min {
        return Err(CoreError::ZeroAmplitude(
            "the averaged output is constant: it has no maximum to time the phase by; check \
             that the input amplitude is not zero and the sensor is connected"
                .into(),
        ));
    }
    Ok(2.0 * PI * j_max as f64 / ybar.len() as f64)
}

/// Largest harmonic below Nyquist for P samples per period: `floor((P - 1)/2)` (0 for P < 3).
pub fn max_harmonics(samples_per_period: usize) -> usize {
    samples_per_period.saturating_sub(1) / 2
}

/// Time derivative (units of `ybar` per second, length P) of one period `ybar` (length P) of a
/// signal of angular frequency `omega` (rad/s), by differentiating its trigonometric interpolant
/// truncated to harmonics `1..=harmonics` (`docs/design.md` §4).
///
/// `c_k = (1/P) sum_j ybar_j e^{-2 pi i jk/P}`, `ydot_j = sum_k 2 Re(i k omega c_k e^{2 pi i jk/P})`,
/// evaluated with FFTs (rustfft, any P): O(P log P), exact up to rounding. The interpolant is periodic, so the
/// derivative is right at the period's edges where a finite difference would wrap badly.
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`] (`harmonics` outside
/// `[1, floor((P-1)/2)]`, i.e. the Nyquist bin is never used; `omega <= 0`).
pub fn spectral_derivative(ybar: &[f64], omega: f64, harmonics: usize) -> Result<Vec<f64>> {
    all_finite("ybar", ybar)?;
    let omega = finite("omega", omega)?;
    let p = ybar.len();
    let k_max = max_harmonics(p);
    if !(1..=k_max).contains(&harmonics) {
        return Err(CoreError::InvalidParameter(format!(
            "harmonics = {harmonics} must be in [1, {k_max}] for {p} samples per period (Nyquist \
             excluded); use fewer harmonics or more samples per period"
        )));
    }
    if omega <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "omega = {omega} rad/s must be > 0"
        )));
    }
    // Forward FFT, multiply harmonic k by i k omega (and its mirror P - k by the conjugate), drop
    // every other bin, inverse FFT: O(P log P) for any P.
    let mut planner = FftPlanner::<f64>::new();
    let mut buf: Vec<Complex<f64>> = ybar.iter().map(|&y| Complex::new(y, 0.0)).collect();
    planner.plan_fft_forward(p).process(&mut buf);
    let mut spec = vec![Complex::new(0.0, 0.0); p];
    let inv_p = 1.0 / p as f64;
    for k in 1..=harmonics {
        let factor = Complex::new(0.0, k as f64 * omega * inv_p);
        spec[k] = buf[k] * factor;
        spec[p - k] = spec[k].conj();
    }
    planner.plan_fft_inverse(p).process(&mut spec);
    let ydot: Vec<f64> = spec.iter().map(|c| c.re).collect();
    if !ydot.iter().all(|v| v.is_finite()) {
        return Err(CoreError::NonFinite(format!(
            "the derivative overflowed (omega = {omega}, max |ybar| = {:e}); rescale ybar or omega",
            ybar.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        )));
    }
    Ok(ydot)
}

/// Gain estimator (27b): `|G| = sum ydot_j chi_j / sum chi_j^2` with
/// `chi_j = s_j (-1 + beta sgn(ydot_j) sgn(ybar_j) |ybar_j|^mu + gamma |ybar_j|^mu)`, the
/// hysteresis parameters `beta`, `gamma`, `mu` already estimated (alpha = 1 model).
///
/// Inputs as [`SlsProblem::new`]. Returns `|G(j omega)|` (units of x per unit of u).
///
/// Errors: those of [`SlsProblem::new`]; [`CoreError::NonFinite`] for NaN/inf `beta`, `gamma`,
/// `mu`; [`CoreError::SingularNormalMatrix`] when `chi` is identically zero.
#[allow(clippy::too_many_arguments)]
pub fn gain_estimate(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    phi: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
) -> Result<f64> {
    let problem = SlsProblem::new(ybar, ydot, amplitude, omega, phi)?;
    let beta = finite("beta", beta)?;
    let gamma = finite("gamma", gamma)?;
    let mu = finite("mu", mu)?;
    let mut pw = vec![0.0; problem.len()];
    problem.powers(mu, &mut pw);
    let (mut num, mut den) = (0.0, 0.0);
    for (((&s, &sg), &p), &yd) in problem
        .s
        .iter()
        .zip(&problem.sign)
        .zip(&pw)
        .zip(&problem.ydot)
    {
        let chi = s * (-1.0 + beta * sg * p + gamma * p);
        num += yd * chi;
        den += chi * chi;
    }
    if den == 0.0 {
        return Err(CoreError::SingularNormalMatrix {
            rcond: 0.0,
            context: "the gain regressor chi of (27b) is identically zero".into(),
        });
    }
    Ok(num / den)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn phase_of_a_shifted_cosine() {
        let p = 360;
        for &j0 in &[0usize, 1, 45, 200, 359] {
            let phi = 2.0 * PI * j0 as f64 / p as f64;
            let y: Vec<f64> = (0..p)
                .map(|j| 0.2 + 1.5 * (2.0 * PI * j as f64 / p as f64 - phi).cos())
                .collect();
            assert_relative_eq!(phase_from_max(&y).unwrap(), phi, epsilon = 1e-12);
        }
        // The first of equal maxima wins.
        assert_relative_eq!(phase_from_max(&[0.0, 1.0, 1.0, 0.0]).unwrap(), PI / 2.0);
        let e = phase_from_max(&[2.0; 8]).unwrap_err();
        assert!(matches!(e, CoreError::ZeroAmplitude(_)), "{e}");
        let e = phase_from_max(&[1.0, 2.0, 3.0]).unwrap_err();
        assert!(matches!(e, CoreError::InsufficientData(_)), "{e}");
        let e = phase_from_max(&[1.0, 2.0, f64::NAN, 0.0]).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
    }

    #[test]
    fn spectral_derivative_of_a_trig_polynomial_is_exact() {
        let omega = 3.0;
        for &p in &[16usize, 17, 100] {
            let th = |j: usize| 2.0 * PI * j as f64 / p as f64;
            // y = 1 + 2 cos(th) - 0.5 sin(3 th) + 0.25 cos(7 th + 1)
            let y: Vec<f64> = (0..p)
                .map(|j| {
                    1.0 + 2.0 * th(j).cos() - 0.5 * (3.0 * th(j)).sin()
                        + 0.25 * (7.0 * th(j) + 1.0).cos()
                })
                .collect();
            let dy: Vec<f64> = (0..p)
                .map(|j| {
                    omega
                        * (-2.0 * th(j).sin()
                            - 1.5 * (3.0 * th(j)).cos()
                            - 1.75 * (7.0 * th(j) + 1.0).sin())
                })
                .collect();
            let got = spectral_derivative(&y, omega, max_harmonics(p)).unwrap();
            for (g, e) in got.iter().zip(&dy) {
                assert_relative_eq!(g, e, epsilon = 1e-12);
            }
            // Truncating at K = 3 drops exactly the 7th harmonic.
            let k3 = spectral_derivative(&y, omega, 3).unwrap();
            for (j, g) in k3.iter().enumerate() {
                let e = dy[j] + omega * 1.75 * (7.0 * th(j) + 1.0).sin();
                assert_relative_eq!(*g, e, epsilon = 1e-12);
            }
        }
    }

    #[test]
    fn spectral_derivative_validation() {
        let y = [0.0, 1.0, 0.0, -1.0, 0.0, 1.0];
        let e = spectral_derivative(&y, 1.0, 3).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        assert!(e.to_string().contains("[1, 2]"), "{e}");
        let e = spectral_derivative(&y, 1.0, 0).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        let e = spectral_derivative(&y, -1.0, 1).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        let e = spectral_derivative(&[], 1.0, 1).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        let e = spectral_derivative(&y, f64::NAN, 1).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        assert_eq!(max_harmonics(0), 0);
        assert_eq!(max_harmonics(4), 1);
        assert_eq!(max_harmonics(1024), 511);
    }
}

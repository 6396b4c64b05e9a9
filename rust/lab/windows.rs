//! The per-period fits of the steady-segment detector (`signal._windows.window_features`, issue
//! #8): a block of a record is cut into period-long windows, and in each the input and the output
//! are fitted on the first `K` harmonics of the block's frequency. The NumPy reference forms the
//! basis and solves the normal equations of every window; here each window's fit is the fused
//! moment fit of [`super::fit`] on the block's phasors (formed once per block).

use super::fit::{fit_of, HarmonicFit};
use super::wide::wide_fn;
use super::{check, check_harmonics, check_omega, Phases, Phasors};
use crate::error::{CoreError, Result};

/// The fits of `u` and `y` in each window of a block.
#[derive(Debug, Clone)]
pub struct WindowFits {
    /// Number of harmonics `K` of each fit (`m = 2K + 1` coefficients).
    pub harmonics: usize,
    /// Per window, `[u coefficients (m), y coefficients (m)]`, row-major `windows x 2m`; NaN
    /// where the window's Gram matrix is too ill-conditioned (the caller's reference path).
    pub coef: Vec<f64>,
    /// Per window, `[rss of u, rss of y]` (NaN as `coef`).
    pub rss: Vec<f64>,
}

/// Fits of `u` and `y` (length n, at the block's phases `theta`) on harmonics `1..=k` and a
/// constant in each window `[starts[i], stops[i])`.
///
/// Errors: non-finite input, unequal lengths, `k < 1`, a window outside `[0, n)` or empty, a window
/// shorter than the `2k + 1` coefficients of its fit.
pub fn window_fits(
    theta: &[f64],
    u: &[f64],
    y: &[f64],
    starts: &[usize],
    stops: &[usize],
    k: usize,
) -> Result<WindowFits> {
    window_fits_at(theta, None, u, y, starts, stops, k)
}

/// [`window_fits`] at the phases `theta`, or at `omega tau` when `omega` (rad/s) is given and
/// `theta` holds the block's times `tau` (s).
///
/// Errors: as [`window_fits`], and a non-finite `omega`.
pub fn window_fits_at(
    theta: &[f64],
    omega: Option<f64>,
    u: &[f64],
    y: &[f64],
    starts: &[usize],
    stops: &[usize],
    k: usize,
) -> Result<WindowFits> {
    check(theta, u, k)?;
    check(theta, y, k)?;
    check_omega(omega)?;
    if starts.len() != stops.len() {
        return Err(CoreError::InvalidParameter(format!(
            "starts and stops must have equal lengths, got {} and {}",
            starts.len(),
            stops.len()
        )));
    }
    if let Some((a, b)) = starts
        .iter()
        .zip(stops)
        .find(|(a, b)| a >= b || **b > theta.len())
    {
        return Err(CoreError::InvalidParameter(format!(
            "window [{a}, {b}) is empty or outside the block of {} samples",
            theta.len()
        )));
    }
    for (a, b) in starts.iter().zip(stops) {
        check_harmonics(b - a, k)?;
    }
    Ok(Phasors::with(|buf, unused| {
        window_fits_wide(theta, omega, u, y, starts, stops, k, buf, unused)
    }))
}

wide_fn! {
    fn window_fits_wide(
        theta: &[f64],
        omega: Option<f64>,
        u: &[f64],
        y: &[f64],
        starts: &[usize],
        stops: &[usize],
        k: usize,
        buf: &mut Phasors,
        unused: &mut Phasors,
    ) -> WindowFits {
        let m = 2 * k + 1;
        let mut coef = vec![f64::NAN; starts.len() * 2 * m];
        let mut rss = vec![f64::NAN; starts.len() * 2];
        // The block's phasors, formed once for every window's fits.
        let z = buf.fill(Phases::of(theta, omega));
        for (i, (&a, &b)) in starts.iter().zip(stops).enumerate() {
            let w = z.sub(a, b);
            let fits: [Option<HarmonicFit>; 2] =
                [fit_of(w, &u[a..b], k, unused), fit_of(w, &y[a..b], k, unused)];
            if let [Some(fu), Some(fy)] = fits {
                coef[i * 2 * m..i * 2 * m + m].copy_from_slice(&fu.coef);
                coef[i * 2 * m + m..(i + 1) * 2 * m].copy_from_slice(&fy.coef);
                rss[2 * i] = fu.rss;
                rss[2 * i + 1] = fy.rss;
            }
        }
        WindowFits { harmonics: k, coef, rss }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_window_is_its_own_fit() {
        let n = 640;
        let p = 63.7;
        let theta: Vec<f64> = (0..n)
            .map(|i| (std::f64::consts::TAU * i as f64 / p).rem_euclid(std::f64::consts::TAU))
            .collect();
        // The amplitude of u doubles after sample 320: the windows see it.
        let u: Vec<f64> = theta
            .iter()
            .enumerate()
            .map(|(i, t)| if i < 320 { 1.0 } else { 2.0 } * t.cos() + 0.1)
            .collect();
        let y: Vec<f64> = theta.iter().map(|t| (2.0 * t).sin()).collect();
        let (starts, stops) = ([0, 64, 330], [63, 127, 393]);
        let f = window_fits(&theta, &u, &y, &starts, &stops, 3).unwrap();
        let m = 7;
        for (i, amp) in [1.0, 1.0, 2.0].iter().enumerate() {
            let row = &f.coef[i * 2 * m..(i + 1) * 2 * m];
            assert!(
                (row[0] - 0.1).abs() < 1e-12 && (row[1] - amp).abs() < 1e-12,
                "{row:?}"
            );
            assert!((row[m + 4] - 1.0).abs() < 1e-12);
            assert!(f.rss[2 * i] < 1e-20 && f.rss[2 * i + 1] < 1e-20);
        }
        assert!(window_fits(&theta, &u, &y, &[5], &[5], 3).is_err());
        assert!(window_fits(&theta, &u, &y, &[5], &[n + 1], 3).is_err());
        assert!(window_fits(&theta, &u, &y, &[5, 6], &[9], 3).is_err());
    }
}

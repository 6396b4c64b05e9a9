//! Periodic averaging (4a-b) of the seed paper (`docs/design.md` §2):
//! `ybar[j] = (1/N) sum_{k=0..N-1} y[(S + k) P + j]`, j = 0..P-1, after dropping S settling
//! periods. Averaging N periods divides the variance of zero-mean noise by N, see (5)-(6).
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use crate::error::{all_finite, CoreError, Result};

/// Fewest samples per period accepted: below this a period cannot show a loading and an
/// unloading branch.
pub const MIN_SAMPLES_PER_PERIOD: usize = 4;

/// Periodic average of `y` (length >= `(settle_periods + periods) samples_per_period`).
///
/// `samples_per_period` = P = T/dt (>= 4), `settle_periods` = S whole periods dropped first,
/// `periods` = N >= 1 periods averaged. Returns `ybar` of length P, in the units of `y`.
///
/// Errors: [`CoreError::NonFinite`] when any sample of `y` is NaN/inf,
/// [`CoreError::InsufficientData`] when P < 4, N < 1 or `y` is too short.
pub fn periodic_average(
    y: &[f64],
    samples_per_period: usize,
    settle_periods: usize,
    periods: usize,
) -> Result<Vec<f64>> {
    all_finite("y", y)?;
    let (p, s, n) = (samples_per_period, settle_periods, periods);
    if p < MIN_SAMPLES_PER_PERIOD {
        return Err(CoreError::InsufficientData(format!(
            "samples_per_period = {p}: at least {MIN_SAMPLES_PER_PERIOD} samples per period are \
             needed; sample faster or excite at a lower frequency"
        )));
    }
    if n < 1 {
        return Err(CoreError::InsufficientData(format!(
            "periods = {n}: at least one period must be averaged"
        )));
    }
    let need = s.checked_add(n).and_then(|sn| sn.checked_mul(p));
    let Some(need) = need.filter(|&need| need <= y.len()) else {
        return Err(CoreError::InsufficientData(format!(
            "the recording has {} samples = {:.2} periods, but {s} settling + {n} averaged \
             periods need {}; record longer or ask for fewer periods",
            y.len(),
            y.len() as f64 / p as f64,
            need.map_or_else(|| "more".to_string(), |v| v.to_string()),
        )));
    };
    let window = &y[s * p..need];
    let mut chunks = window.chunks_exact(p);
    // Summed period by period (as numpy's mean over axis 0), then divided once.
    let mut ybar = chunks.next().map(<[f64]>::to_vec).unwrap_or_default();
    for chunk in chunks {
        for (acc, v) in ybar.iter_mut().zip(chunk) {
            *acc += v;
        }
    }
    let count = n as f64;
    for v in &mut ybar {
        *v /= count;
    }
    Ok(ybar)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn averages_out_an_alternating_disturbance() {
        // Periodic part + a disturbance that alternates sign from one period to the next: over an
        // even number of periods it cancels exactly. A transient fills the settling periods.
        let p = 16;
        let (s, n) = (3, 10);
        let periodic = |j: usize| (2.0 * std::f64::consts::PI * j as f64 / p as f64).sin() + 0.3;
        let y: Vec<f64> = (0..(s + n) * p + 5)
            .map(|i| {
                let (period, j) = (i / p, i % p);
                let sign = if period % 2 == 0 { 1.0 } else { -1.0 };
                let transient = if period < s { 100.0 } else { 0.0 };
                periodic(j) + sign * 0.7 * (j as f64 + 1.0) + transient
            })
            .collect();
        let ybar = periodic_average(&y, p, s, n).unwrap();
        assert_eq!(ybar.len(), p);
        for (j, &v) in ybar.iter().enumerate() {
            assert_relative_eq!(v, periodic(j), epsilon = 1e-14);
        }
        // One period: the average is that period.
        let one = periodic_average(&y, p, s, 1).unwrap();
        assert_eq!(one, y[s * p..(s + 1) * p].to_vec());
    }

    #[test]
    fn validation() {
        let y = vec![1.0; 40];
        let insufficient = |r: Result<Vec<f64>>, text: &str| {
            let e = r.unwrap_err();
            assert!(matches!(e, CoreError::InsufficientData(_)), "{e}");
            assert!(e.to_string().contains(text), "{e}");
        };
        insufficient(periodic_average(&y, 3, 0, 1), "samples_per_period = 3");
        insufficient(periodic_average(&y, 4, 0, 0), "periods = 0");
        insufficient(periodic_average(&y, 8, 2, 4), "need 48");
        insufficient(periodic_average(&y, 8, usize::MAX, 4), "need more");
        assert!(periodic_average(&y, 8, 1, 4).is_ok());
        let mut bad = y.clone();
        bad[39] = f64::NAN;
        let e = periodic_average(&bad, 8, 0, 1).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        assert!(e.to_string().contains("index 39"), "{e}");
    }
}

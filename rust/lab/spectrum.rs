//! The zero-padded, Hann-windowed magnitude spectrum of the sine analysis's first frequency guess
//! (`signal._sine.dft_peak`, issue #8): the record detrended (mean and least-squares slope),
//! windowed, padded to `nfft` and transformed. The NumPy reference (`np.fft.rfft`) transforms
//! `nfft` reals; here the reals are packed into `nfft/2` complex numbers, transformed by rustfft
//! (planned once per length and cached) and unpacked, half the work, and [`spectral_peak`]
//! chooses the bin as the reference does without handing the spectrum back.

use std::cell::RefCell;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use super::sincos::sincos;
use super::wide::wide_fn;
use crate::error::{all_finite, CoreError, Result};

/// A plan for the complex transform of length `nfft/2`, and the unpacking twiddles
/// `e^{-2 pi i k / nfft}`, `k < nfft/2`.
type Plan = (Arc<dyn Fft<f64>>, Arc<Vec<Complex<f64>>>);

fn plan(nfft: usize) -> Plan {
    static PLANS: OnceLock<Mutex<HashMap<usize, Plan>>> = OnceLock::new();
    let plans = PLANS.get_or_init(|| Mutex::new(HashMap::new()));
    // A poisoned lock only means another thread panicked while planning: the map is still valid.
    let mut map = plans.lock().unwrap_or_else(|e| e.into_inner());
    map.entry(nfft)
        .or_insert_with(|| {
            let half = nfft / 2;
            let fft = FftPlanner::<f64>::new().plan_fft_forward(half);
            let tw = (0..half)
                .map(|k| Complex::from_polar(1.0, -2.0 * PI * k as f64 / nfft as f64))
                .collect();
            (fft, Arc::new(tw))
        })
        .clone()
}

/// `|rfft(w (x - mean - slope idx), nfft)|` (length `nfft/2 + 1`): `idx = i - (n-1)/2`, `slope` the
/// least-squares slope of `x` on `idx`, `w` the Hann window `0.5 - 0.5 cos(2 pi i / (n-1))` (NumPy's
/// `hanning`), zero padding to `nfft` (even, `>= n`).
///
/// Errors: non-finite `x`, fewer than 2 samples, `nfft` odd, shorter than `x` or more than 16 times
/// longer (zero padding beyond that buys nothing but memory).
pub fn padded_spectrum(x: &[f64], nfft: usize) -> Result<Vec<f64>> {
    with_spectrum(x, nfft, |s| s.to_vec())
}

/// The bin of [`padded_spectrum`] that `signal._sine.dft_peak` takes, with its neighbours:
/// `(k, |X_{k-1}|, |X_k|, |X_{k+1}|)`. `k` is the first largest bin of `[lo, hi]`, unless the
/// first largest of the band `[band_lo, band_hi]` (no band when `band_hi <= band_lo`) is a strict
/// local maximum of at least `peak_min` times it.
///
/// Errors: as [`padded_spectrum`], and bins outside `[1, nfft/2 - 1]` or `hi < lo`.
#[allow(clippy::too_many_arguments)]
pub fn spectral_peak(
    x: &[f64],
    nfft: usize,
    lo: usize,
    hi: usize,
    band_lo: usize,
    band_hi: usize,
    peak_min: f64,
) -> Result<(usize, f64, f64, f64)> {
    let band = band_hi > band_lo;
    let top = nfft / 2;
    if lo < 1 || hi < lo || hi + 1 > top || (band && (band_lo < 1 || band_hi + 1 > top)) {
        return Err(CoreError::InvalidParameter(format!(
            "bins [{lo}, {hi}] (band [{band_lo}, {band_hi}]) must lie in [1, {}]",
            top.saturating_sub(1)
        )));
    }
    with_spectrum(x, nfft, |s| {
        let first_max =
            |a: usize, b: usize| (a..=b).fold(a, |best, i| if s[i] > s[best] { i } else { best });
        let mut k = first_max(lo, hi);
        if band {
            let kb = first_max(band_lo, band_hi);
            if s[kb - 1] < s[kb] && s[kb] > s[kb + 1] && s[kb] >= peak_min * s[k] {
                k = kb;
            }
        }
        (k, s[k - 1], s[k], s[k + 1])
    })
}

/// `f` of the spectrum of [`padded_spectrum`], computed in buffers kept per thread: fresh
/// megabytes cost more in page faults than the transform.
fn with_spectrum<R>(x: &[f64], nfft: usize, f: impl FnOnce(&[f64]) -> R) -> Result<R> {
    all_finite("x", x)?;
    let n = x.len();
    if n < 2 || nfft < n || nfft % 2 != 0 || nfft / 16 > n {
        return Err(CoreError::InvalidParameter(format!(
            "nfft = {nfft} must be even, >= the {n} samples (at least 2) and at most 16 times as many"
        )));
    }
    let (fft, tw) = plan(nfft);
    thread_local! {
        static PACKED: RefCell<Vec<Complex<f64>>> = const { RefCell::new(Vec::new()) };
        static SPECTRUM: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    }
    Ok(PACKED.with_borrow_mut(|z| {
        pack(x, nfft / 2, z);
        fft.process(z);
        SPECTRUM.with_borrow_mut(|out| {
            unpack(z, &tw, out);
            f(out)
        })
    }))
}

wide_fn! {
    /// Into `z` (`half` complex numbers), the detrended, Hann-windowed, zero-padded record `x`
    /// packed two reals at a time.
    fn pack(x: &[f64], half: usize, z: &mut Vec<Complex<f64>>) -> () {
        let n = x.len();
        let centre = 0.5 * (n as f64 - 1.0);
        let (mut sxx, mut sxy, mut sum) = (0.0, 0.0, 0.0);
        for (i, v) in x.iter().enumerate() {
            let d = i as f64 - centre;
            sxx += d * d;
            sxy += d * v;
            sum += v;
        }
        let (slope, mean) = (sxy / sxx, sum / n as f64);
        let step = 2.0 * PI / (n as f64 - 1.0);
        z.clear();
        z.resize(half, Complex::new(0.0, 0.0));
        // Safe view of the packed numbers as 2 half reals (Complex<f64> is repr(C) [re, im]).
        let flat: &mut [f64] = as_reals(z);
        for (i, (o, v)) in flat.iter_mut().zip(x).enumerate() {
            let w = 0.5 - 0.5 * sincos(step * i as f64).1;
            *o = w * (v - mean - slope * (i as f64 - centre));
        }
    }
}

/// The complex numbers of `z` as their real and imaginary parts in turn.
fn as_reals(z: &mut [Complex<f64>]) -> &mut [f64] {
    let len = 2 * z.len();
    // SAFETY: `Complex<f64>` is `#[repr(C)]` with two `f64` fields (re, im), so a slice of them is a
    // slice of twice as many `f64`, with the same alignment; the borrow is carried over.
    unsafe { std::slice::from_raw_parts_mut(z.as_mut_ptr().cast::<f64>(), len) }
}

wide_fn! {
    /// Into `out`, the magnitude spectrum (`h + 1` bins) of the `2 h` reals packed in `z` (length
    /// `h`, transformed): `X_k = E_k + e^{-2 pi i k/(2h)} O_k`, `E_k = (Z_k + conj Z_{h-k})/2`,
    /// `O_k = (Z_k - conj Z_{h-k})/(2i)`.
    fn unpack(z: &[Complex<f64>], tw: &[Complex<f64>], out: &mut Vec<f64>) -> () {
        let half = z.len();
        out.clear();
        out.resize(half + 1, 0.0);
        // Bin k pairs Z_k with Z_{h-k}: bins 1..h-1 in one sweep, 0 and h apart.
        let edge = |a: Complex<f64>, t: Complex<f64>| {
            let b = a.conj();
            let e = (a + b) * 0.5;
            let o = (a - b) * Complex::new(0.0, -0.5);
            (e + t * o).norm_sqr().sqrt()
        };
        out[0] = edge(z[0], Complex::new(1.0, 0.0));
        out[half] = edge(z[0], Complex::new(-1.0, 0.0));
        for k in 1..half {
            let (a, b) = (z[k], z[half - k].conj());
            let (er, ei) = (0.5 * (a.re + b.re), 0.5 * (a.im + b.im));
            // (a - b) / (2i) = ((a - b).im / 2) - i ((a - b).re / 2).
            let (or, oi) = (0.5 * (a.im - b.im), -0.5 * (a.re - b.re));
            let t = tw[k];
            let (xr, xi) = (er + t.re * or - t.im * oi, ei + t.re * oi + t.im * or);
            // sqrt(re^2 + im^2): no overflow at these magnitudes, and much faster than hypot.
            out[k] = (xr * xr + xi * xi).sqrt();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_direct_dft_and_validates() {
        let n = 37;
        let x: Vec<f64> = (0..n)
            .map(|i| (0.9 * i as f64).cos() + 0.01 * i as f64 + 0.3)
            .collect();
        let nfft = 128;
        let spec = padded_spectrum(&x, nfft).unwrap();
        assert_eq!(spec.len(), nfft / 2 + 1);
        // The detrended, windowed record by the formulas, and its DFT bin by bin.
        let c = 0.5 * (n as f64 - 1.0);
        let idx: Vec<f64> = (0..n).map(|i| i as f64 - c).collect();
        let slope = idx.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>()
            / idx.iter().map(|a| a * a).sum::<f64>();
        let mean = x.iter().sum::<f64>() / n as f64;
        for (k, s) in spec.iter().enumerate() {
            let mut acc = Complex::new(0.0, 0.0);
            for i in 0..n {
                let w = 0.5 - 0.5 * (2.0 * PI * i as f64 / (n as f64 - 1.0)).cos();
                let v = w * (x[i] - mean - slope * idx[i]);
                acc += Complex::from_polar(v, -2.0 * PI * (k * i) as f64 / nfft as f64);
            }
            assert!(
                (acc.norm() - s).abs() < 1e-12,
                "bin {k}: {} vs {s}",
                acc.norm()
            );
        }
        assert!(padded_spectrum(&x, 127).is_err());
        assert!(padded_spectrum(&x, 32).is_err());
        assert!(padded_spectrum(&[1.0], 2).is_err());
        assert!(padded_spectrum(&[1.0, f64::NAN], 4).is_err());
        // The peak: the largest bin, or the band's local maximum when it is large enough.
        let (k, a, b, c) = spectral_peak(&x, nfft, 4, 62, 0, 0, 0.1).unwrap();
        let kmax = (4..=62).fold(4, |m, i| if spec[i] > spec[m] { i } else { m });
        assert_eq!((k, a, b, c), (kmax, spec[k - 1], spec[k], spec[k + 1]));
        assert!(spectral_peak(&x, nfft, 0, 62, 0, 0, 0.1).is_err());
        assert!(spectral_peak(&x, nfft, 4, 64, 0, 0, 0.1).is_err());
    }
}

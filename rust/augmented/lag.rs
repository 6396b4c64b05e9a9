//! The augmented model's output stage: the sensor lag `tau ydot + y = F` in its periodic steady
//! state, applied on the DFT of the period (and its derivative in `tau`), then the offset.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::cell::RefCell;

/// The lag filter of bin `n` of a P-point DFT at `tau`, and its derivative in `tau`.
///
/// Harmonic `k = n` for `n < P/2`, `n - P` above; the Nyquist bin of an even P takes the real
/// `Re 1/(1 + i (P/2) omega tau)` so that the output stays real.
fn lag_bin(n: usize, p: usize, omega: f64, tau: f64) -> (Complex<f64>, Complex<f64>) {
    let one = Complex::new(1.0, 0.0);
    if 2 * n == p {
        let a = (p / 2) as f64 * omega;
        let d = 1.0 + a * a * tau * tau;
        return (
            Complex::new(1.0 / d, 0.0),
            Complex::new(-2.0 * a * a * tau / (d * d), 0.0),
        );
    }
    let k = if 2 * n < p {
        n as f64
    } else {
        n as f64 - p as f64
    };
    let iw = Complex::new(0.0, k * omega);
    let den = one + iw * tau;
    let h = one / den;
    (h, -iw * h * h)
}

thread_local! {
    /// The lag filter's FFT plans, kept per thread by size (issue 18 item 4): planned afresh on
    /// every call, a prime size (the MR damper's P = 401, 37: Bluestein) cost more than the
    /// transforms. A size always gets the same algorithm, so the outputs are the same bit for bit.
    static LAG_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// Applies the lag (`derivative == false`) or its tau-derivative to real columns in place, two
/// columns per complex FFT (the filter is Hermitian, so it maps the real and imaginary parts
/// separately).
pub(super) fn apply_lag(cols: &mut [&mut [f64]], omega: f64, tau: f64, derivative: bool) {
    let Some(first) = cols.first() else {
        return;
    };
    let p = first.len();
    let (fwd, inv) = LAG_PLANNER.with(|planner| {
        let mut planner = planner.borrow_mut();
        (planner.plan_fft_forward(p), planner.plan_fft_inverse(p))
    });
    let filt: Vec<Complex<f64>> = (0..p)
        .map(|n| {
            let (h, dh) = lag_bin(n, p, omega, tau);
            if derivative {
                dh
            } else {
                h
            }
        })
        .collect();
    let scale = 1.0 / p as f64;
    let mut buf = vec![Complex::new(0.0, 0.0); p];
    for pair in cols.chunks_mut(2) {
        for (j, z) in buf.iter_mut().enumerate() {
            let im = if pair.len() > 1 { pair[1][j] } else { 0.0 };
            *z = Complex::new(pair[0][j], im);
        }
        fwd.process(&mut buf);
        for (z, h) in buf.iter_mut().zip(&filt) {
            *z *= h * scale;
        }
        inv.process(&mut buf);
        for (j, z) in buf.iter().enumerate() {
            pair[0][j] = z.re;
            if pair.len() > 1 {
                pair[1][j] = z.im;
            }
        }
    }
}

/// The output stage of [`augmented_output_with`] on the work space `cols` (F, then the shared
/// columns, then g and phi, each of P samples): the sensor lag filters every column but its own
/// and the offset's, its own column becomes `dY/dtau`; the offset is added after the lag, its
/// column is 1. `lag_col`, `offset_col` index `cols` (the parameter is `shared[col - 1]`).
pub(super) fn lag_and_offset(
    cols: &mut [Vec<f64>],
    shared: &[f64],
    omega: f64,
    lag_col: Option<usize>,
    offset_col: Option<usize>,
) {
    if let Some(lc) = lag_col {
        let tau = shared[lc - 1];
        let mut dtau = cols[0].clone();
        apply_lag(&mut [&mut dtau[..]], omega, tau, true);
        let mut filtered: Vec<&mut [f64]> = cols
            .iter_mut()
            .enumerate()
            .filter(|&(c, _)| Some(c) != lag_col && Some(c) != offset_col)
            .map(|(_, v)| &mut v[..])
            .collect();
        apply_lag(&mut filtered, omega, tau, false);
        cols[lc] = dtau;
    }
    if let Some(oc) = offset_col {
        let y0 = shared[oc - 1];
        cols[0].iter_mut().for_each(|v| *v += y0);
        cols[oc].iter_mut().for_each(|v| *v = 1.0);
    }
}

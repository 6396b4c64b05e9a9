//! `(sin x, cos x)` for whole arrays, written so that the compiler vectorises it (issue #8): the
//! harmonic fits of the lab preprocessing start every pass over a record from `e^{i theta_n}`, and
//! the scalar `libm` calls cost more than the rest of a one-harmonic fit.
//!
//! Cody-Waite reduction by `pi/2` in three parts (exact for `|x| < 2^19 pi/2`, far beyond the
//! phases of a record, which the callers keep within a few hundred radians) and the minimax
//! polynomials of Cephes' `sin.c` on `[-pi/4, pi/4]`; quadrant selection by comparisons, no
//! branches. Error below 2 ulp of 1 against `libm` (tested on a million points); arguments
//! beyond the exact range go to `libm`.

// The constants are written with all the digits of their sources.
#![allow(clippy::excessive_precision)]

/// `pi/2` in three parts (fdlibm's `pio2_1`, `pio2_2`, `pio2_2t`): the first two hold 33 bits
/// each, so `j * part` is exact for `|j| < 2^20`.
const PIO2_1: f64 = 1.570_796_326_734_125_614_17e0;
const PIO2_2: f64 = 6.077_100_506_303_965_976_6e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_631_54e-21;
/// Largest `|x|` reduced here (`2^19 pi/2`); beyond it, `libm`.
const REDUCE_MAX: f64 = 823_549.6;

const S: [f64; 6] = [
    1.589_623_015_765_465_680_60e-10,
    -2.505_074_776_285_780_728_66e-8,
    2.755_731_362_138_572_452_13e-6,
    -1.984_126_982_958_953_859_96e-4,
    8.333_333_333_322_118_588_78e-3,
    -1.666_666_666_666_663_072_95e-1,
];
const C: [f64; 6] = [
    -1.135_853_652_138_768_173_00e-11,
    2.087_570_084_197_473_167_78e-9,
    -2.755_731_417_929_673_881_12e-7,
    2.480_158_728_885_170_453_48e-5,
    -1.388_888_888_887_305_641_16e-3,
    4.166_666_666_666_659_292_18e-2,
];

/// `(sin x, cos x)` of one argument, branch-free for `|x| <= REDUCE_MAX` (inlined into the array
/// loops, where it vectorises).
#[inline(always)]
pub fn sincos(x: f64) -> (f64, f64) {
    let j = (x * std::f64::consts::FRAC_2_PI).round_ties_even();
    let r = ((x - j * PIO2_1) - j * PIO2_2) - j * PIO2_3;
    let z = r * r;
    let ps = ((((S[0] * z + S[1]) * z + S[2]) * z + S[3]) * z + S[4]) * z + S[5];
    let pc = ((((C[0] * z + C[1]) * z + C[2]) * z + C[3]) * z + C[4]) * z + C[5];
    let s = r + r * z * ps;
    let c = 1.0 - 0.5 * z + z * z * pc;
    // Quadrant q = j mod 4, its parity and signs, in floating point and without selects (so that
    // the compiler vectorises it): odd quadrants swap sin and cos; sin < 0 in quadrants 2, 3 and
    // cos < 0 in quadrants 1, 2. Multiplying by 0 or 1 and adding is exact.
    let q = j - 4.0 * (j * 0.25).floor();
    let half = (q * 0.5).floor();
    let odd = q - 2.0 * half;
    let even = 1.0 - odd;
    let q1 = q + 1.0;
    let sign_c = 1.0 - 2.0 * ((q1 - 4.0 * (q1 * 0.25).floor()) * 0.5).floor();
    let sin = (1.0 - 2.0 * half) * (even * s + odd * c);
    let cos = sign_c * (even * c + odd * s);
    (sin, cos)
}

/// `out_sin[i], out_cos[i] = sin x[i], cos x[i]` (the slices have equal lengths).
#[inline(always)]
pub fn sincos_into(x: &[f64], out_sin: &mut [f64], out_cos: &mut [f64]) {
    let n = x.len().min(out_sin.len()).min(out_cos.len());
    let (x, out_sin, out_cos) = (&x[..n], &mut out_sin[..n], &mut out_cos[..n]);
    let mut far = false;
    for i in 0..n {
        let (s, c) = sincos(x[i]);
        out_sin[i] = s;
        out_cos[i] = c;
        far |= x[i].abs() > REDUCE_MAX;
    }
    if far {
        for i in 0..n {
            if x[i].abs() > REDUCE_MAX {
                (out_sin[i], out_cos[i]) = x[i].sin_cos();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_libm_to_two_ulp_of_one() {
        // A deterministic spread over [-1000, 1000] and the quadrant boundaries.
        let mut xs: Vec<f64> = (0..1_000_000)
            .map(|i| ((i as f64) * 0.618_033_988_749_895).fract() * 2000.0 - 1000.0)
            .collect();
        for k in -40..=40 {
            let b = k as f64 * std::f64::consts::FRAC_PI_2;
            xs.extend([b, b.next_up(), b.next_down(), b + 1e-9, b - 1e-9]);
        }
        xs.extend([0.0, -0.0, 1e6, -3e7, 1e-300]);
        let (mut s, mut c) = (vec![0.0; xs.len()], vec![0.0; xs.len()]);
        sincos_into(&xs, &mut s, &mut c);
        let mut worst: f64 = 0.0;
        for ((x, s), c) in xs.iter().zip(&s).zip(&c) {
            let (es, ec) = x.sin_cos();
            worst = worst.max((s - es).abs()).max((c - ec).abs());
        }
        assert!(worst <= 2.0 * f64::EPSILON, "worst error {worst:e}");
    }
}

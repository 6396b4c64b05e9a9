//! A measured input's waveform beyond its fundamental (design.md 9.5) and its reversals.

use std::f64::consts::PI;

/// Grid points per period (at least, and per highest harmonic) on which the reversals of a
/// distorted waveform are bracketed: the sign changes of `xi'` on the grid; a harmonic k turns at
/// most `2k` times per period, so 8 points per highest harmonic's period separate its roots
/// unless two nearly coincide (a nearly flat inflection, whose loop contribution is nil).
pub(super) const REVERSAL_GRID_MIN: usize = 64;

/// See [`REVERSAL_GRID_MIN`].
pub(super) const REVERSAL_GRID_PER_HARMONIC: usize = 8;

/// Safeguarded Newton steps allowed per reversal (bisection alone reaches 1e-15 rad in ~50).
pub(super) const REVERSAL_MAX_ITER: usize = 100;

/// A measured input's waveform beyond its fundamental (design.md 9.5): the latent input is
/// `x = A xi(theta - phi)`, `xi(zeta) = cos(zeta) + lambda d(zeta)`, with the normalised
/// distortion `d(zeta) = sum_{k >= 2} Re(c_k e^{i k zeta})` measured on the input (`c_k` relative
/// to the fundamental's amplitude and phase) and `lambda` the fitted scale (1: the measured
/// waveform drives the model; 0: the pure sine).
#[derive(Debug, Clone, Copy)]
pub struct Waveform<'a> {
    /// `lambda` (dimensionless).
    pub lambda: f64,
    /// `[Re c_2, Im c_2, Re c_3, Im c_3, ...]` (dimensionless, relative to the fundamental).
    pub harmonics: &'a [f64],
}

impl Waveform<'_> {
    /// `[xi, xi', xi'', d]` at `zeta` (derivatives in zeta).
    pub(super) fn eval(&self, zeta: f64) -> [f64; 4] {
        let (mut d, mut d1, mut d2) = (0.0, 0.0, 0.0);
        for (i, c) in self.harmonics.chunks_exact(2).enumerate() {
            let k = (i + 2) as f64;
            let (s, co) = (k * zeta).sin_cos();
            let v = c[0] * co - c[1] * s;
            d += v;
            d1 -= k * (c[0] * s + c[1] * co);
            d2 -= k * k * v;
        }
        let (s, co) = zeta.sin_cos();
        let l = self.lambda;
        [co + l * d, -s + l * d1, -co + l * d2, d]
    }

    /// The reversals of `xi` (roots of `xi'`) in `[0, 2 pi)`: sign changes on a grid, each
    /// refined by Newton safeguarded by bisection in its bracket.
    pub(super) fn reversals(&self) -> Vec<f64> {
        let m = REVERSAL_GRID_MIN.max(REVERSAL_GRID_PER_HARMONIC * (self.harmonics.len() / 2 + 1));
        let h = 2.0 * PI / m as f64;
        let f = |z: f64| self.eval(z)[1];
        let mut roots = Vec::new();
        for i in 0..m {
            let (mut lo, mut hi) = (i as f64 * h, (i + 1) as f64 * h);
            let (flo, fhi) = (f(lo), f(hi));
            if flo == 0.0 {
                roots.push(lo);
                continue;
            }
            if flo * fhi >= 0.0 {
                continue;
            }
            let mut z = 0.5 * (lo + hi);
            for _ in 0..REVERSAL_MAX_ITER {
                let e = self.eval(z);
                if e[1] == 0.0 {
                    break;
                }
                if (e[1] < 0.0) == (flo < 0.0) {
                    lo = z;
                } else {
                    hi = z;
                }
                let newton = z - e[1] / e[2];
                let next = if newton > lo && newton < hi {
                    newton
                } else {
                    0.5 * (lo + hi)
                };
                let done = (next - z).abs() <= 4.0 * f64::EPSILON * (1.0 + z.abs());
                z = next;
                if done || hi - lo <= 4.0 * f64::EPSILON * (1.0 + z.abs()) {
                    break;
                }
            }
            roots.push(z);
        }
        roots
    }
}

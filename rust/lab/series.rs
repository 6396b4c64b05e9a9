//! The fitted harmonic series on a record, block by block: its values, the residual sum of squares
//! against the record, and the Gauss-Newton terms of the frequency fit.

use super::moments::{split_point, SPLIT_WORK};
use super::phasors::{advance, fold_into, fold_product_into, unfold, Block, Phases};
use super::phasors::{FOLD, LANES};
use super::wide::wide_fn;

/// The series `coef[0] + sum_k coef[2k-1] Re p_k + coef[2k] Im p_k` of one block, `p_k = z^k`.
#[inline(always)]
pub(super) fn block_series(b: &Block, coef: &[f64]) -> [f64; LANES] {
    let mut out = [coef[0]; LANES];
    let (mut pr, mut pi) = (b.zr, b.zi);
    for k in 1..=coef.len() / 2 {
        let (a, c) = (coef[2 * k - 1], coef[2 * k]);
        for l in 0..LANES {
            out[l] += a * pr[l] + c * pi[l];
        }
        advance(&mut pr, &mut pi, &b.zr, &b.zi);
    }
    out
}

/// `sum_n (y_n - series_n)^2` from the record's phasors (see [`harmonic_rss`]).
#[inline(always)]
pub(crate) fn rss_of(z: Phases<'_>, y: &[f64], coef: &[f64]) -> f64 {
    let n = z.len();
    if n * coef.len() >= SPLIT_WORK {
        let mid = split_point(n);
        let (a, b) = rayon::join(
            || rss_part(z.sub(0, mid), &y[..mid], coef),
            || rss_part(z.sub(mid, n), &y[mid..], coef),
        );
        return a + b;
    }
    rss_part(z, y, coef)
}

wide_fn! {
    /// [`rss_of`] over one part of a record.
    pub(super) fn rss_part(z: Phases<'_>, y: &[f64], coef: &[f64]) -> f64 {
        let mut acc = [0.0; LANES];
        for start in (0..z.len()).step_by(LANES) {
            let b = Block::load(z, y, None, start);
            let s = block_series(&b, coef);
            if b.lanes == LANES {
                for l in 0..LANES {
                    let r = b.y[l] - s[l];
                    acc[l] += r * r;
                }
            } else {
                for l in 0..b.lanes {
                    let r = b.y[l] - s[l];
                    acc[l] += r * r;
                }
            }
        }
        acc.iter().sum()
    }
}

/// The terms of [`harmonic_gauss_newton`] from the record's phasors.
#[inline(always)]
pub(crate) fn gauss_newton_of(
    z: Phases<'_>,
    tau: &[f64],
    x: &[f64],
    coef: &[f64],
) -> (f64, f64, f64, Vec<f64>) {
    let kmax = coef.len() / 2;
    let (mut rr, mut rd, mut dd) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    let mut xtd = vec![[0.0; FOLD]; 2 * kmax + 1];
    for start in (0..z.len()).step_by(LANES) {
        let b = Block::load(z, x, Some(tau), start);
        // First sweep over the harmonics: the fitted series and its phase derivative.
        let mut fitted = [coef[0]; LANES];
        let mut slope = [0.0; LANES];
        let (mut pr, mut pi) = (b.zr, b.zi);
        for k in 1..=kmax {
            let (a, c, kf) = (coef[2 * k - 1], coef[2 * k], k as f64);
            for l in 0..LANES {
                fitted[l] += a * pr[l] + c * pi[l];
                slope[l] += kf * (c * pr[l] - a * pi[l]);
            }
            advance(&mut pr, &mut pi, &b.zr, &b.zi);
        }
        // Padding lanes have tau = 0, hence d = 0; their residual is masked out.
        let mut d = [0.0; LANES];
        for l in 0..LANES {
            d[l] = b.tau[l] * slope[l];
        }
        for l in 0..b.lanes {
            let r = b.y[l] - fitted[l];
            rr[l] += r * r;
            rd[l] += r * d[l];
            dd[l] += d[l] * d[l];
        }
        fold_into(&mut xtd[0], &d);
        // Second sweep: the projections of d on the basis.
        let (mut pr, mut pi) = (b.zr, b.zi);
        for k in 1..=kmax {
            fold_product_into(&mut xtd[2 * k - 1], &d, &pr);
            fold_product_into(&mut xtd[2 * k], &d, &pi);
            advance(&mut pr, &mut pi, &b.zr, &b.zi);
        }
    }
    let sum = |a: [f64; LANES]| a.iter().sum::<f64>();
    (sum(rr), sum(rd), sum(dd), unfold(&xtd))
}

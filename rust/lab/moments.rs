//! The complex moments of a record: `mu_q = sum_n z_n^q` and `r_q = sum_n y_n conj(z_n)^q` by the
//! phasor recurrence (from the block template's powers where the time axis is uniform), split
//! between two threads on long records.

use super::phasors::{advance, fold_into, fold_product_into, unfold, Block, Phases, Template};
use super::phasors::{FOLD, LANES};
use super::wide::wide_fn;

/// The moments of [`harmonic_moments`] from the record's phasors.
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(crate) fn moments_of(
    z: Phases<'_>,
    y: &[f64],
    kmax: usize,
) -> ((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>)) {
    let n = z.len();
    // With a block template the moments mu_q come from the blocks' first phasors (below); the
    // samples are visited for r_q alone.
    let templated = match z {
        Phases::Cached(re, im, Some(t)) => Some((re, im, t)),
        _ => None,
    };
    let want_mu = templated.is_none();
    let parts = if n * (2 * kmax + 1) >= SPLIT_WORK {
        // Two halves on two threads (a fixed split: the same sums whatever the pool's size).
        let mid = split_point(n);
        let (a, b) = rayon::join(
            || moments_part(z.sub(0, mid), &y[..mid], kmax, want_mu),
            || moments_part(z.sub(mid, n), &y[mid..], kmax, want_mu),
        );
        a.into_iter()
            .zip(b)
            .map(|(u, v)| u.iter().zip(&v).map(|(p, q)| p + q).collect())
            .collect()
    } else {
        moments_part(z, y, kmax, want_mu)
    };
    let [mut mr, mut mi, rr, ri]: [Vec<f64>; 4] = parts.try_into().expect("four moment arrays");
    if let Some((re, im, t)) = templated {
        (mr, mi) = templated_mu(re, im, t, kmax);
    }
    ((mr, mi), (rr, ri))
}

/// `mu_q = sum_n z_n^q`, `q <= 2 kmax`, of phasors whose blocks of [`LANES`] are their first
/// phasor `s_b` times the template `w_l`: `z_{bL+l}^q = s_b^q w_l^q`, so `mu_q = (sum_b s_b^q)
/// (sum_l w_l^q)` over the whole blocks, plus the last block's partial template sum. The sum over
/// samples becomes one over blocks: 16 times less work. Rounding: `q eps` relative per term, as
/// the per-sample recurrence.
#[inline(always)]
pub(super) fn templated_mu(
    re: &[f64],
    im: &[f64],
    t: &Template,
    kmax: usize,
) -> (Vec<f64>, Vec<f64>) {
    let (n, nq) = (re.len(), 2 * kmax + 1);
    let (nb, rem) = (n / LANES, n % LANES);
    // Template power sums, over all lanes and over the last block's lanes.
    let (mut tf, mut tp) = (vec![(0.0, 0.0); nq], vec![(0.0, 0.0); nq]);
    let (mut pr, mut pi) = ([1.0; LANES], [0.0; LANES]);
    for q in 0..nq {
        tf[q] = (pr.iter().sum(), pi.iter().sum());
        tp[q] = (pr[..rem].iter().sum(), pi[..rem].iter().sum());
        advance(&mut pr, &mut pi, &t.re, &t.im);
    }
    // Power sums of the whole blocks' first phasors: the moment kernel on them (r unused).
    let starts_re: Vec<f64> = (0..nb).map(|b| re[b * LANES]).collect();
    let starts_im: Vec<f64> = (0..nb).map(|b| im[b * LANES]).collect();
    let sums = if nb > 0 {
        moments_part(
            Phases::Cached(&starts_re, &starts_im, None),
            &starts_re,
            kmax,
            true,
        )
    } else {
        vec![vec![0.0; nq], vec![0.0; nq]]
    };
    let (mut last_re, mut last_im) = (1.0, 0.0);
    let (zl_re, zl_im) = if rem > 0 {
        (re[nb * LANES], im[nb * LANES])
    } else {
        (0.0, 0.0)
    };
    let (mut out_re, mut out_im) = (vec![0.0; nq], vec![0.0; nq]);
    for q in 0..nq {
        let (sr, si) = (sums[0][q], sums[1][q]);
        let (fr, fi) = tf[q];
        out_re[q] = sr * fr - si * fi;
        out_im[q] = sr * fi + si * fr;
        if rem > 0 {
            let (gr, gi) = tp[q];
            out_re[q] += last_re * gr - last_im * gi;
            out_im[q] += last_re * gi + last_im * gr;
            (last_re, last_im) = (
                last_re * zl_re - last_im * zl_im,
                last_re * zl_im + last_im * zl_re,
            );
        }
    }
    (out_re, out_im)
}

/// Records at least this long (samples times harmonics, about half a millisecond of work) have
/// their passes split between two threads (`rayon::join`, issue #8: both cores for the synchronous average's long fits); in the
/// batch's worker processes the pool has one thread and the halves run one after the other.
pub(super) const SPLIT_WORK: usize = 1 << 20;

/// Where a record of `n` samples is split in two: the middle, rounded to whole blocks.
pub(super) fn split_point(n: usize) -> usize {
    (n / 2).div_ceil(LANES) * LANES
}

wide_fn! {
    /// `[mu_re, mu_im, r_re, r_im]` of [`moments_of`] over one part of a record (the `mu` all
    /// zero unless `want_mu`).
    pub(super) fn moments_part(z: Phases<'_>, y: &[f64], kmax: usize, want_mu: bool) -> Vec<Vec<f64>> {
        let nq = 2 * kmax + 1;
        let nmu = if want_mu { nq } else { 0 };
        let (mut mu_re, mut mu_im) = (vec![[0.0; FOLD]; nmu], vec![[0.0; FOLD]; nmu]);
        let (mut r_re, mut r_im) = (vec![[0.0; FOLD]; kmax + 1], vec![[0.0; FOLD]; kmax + 1]);
        for start in (0..z.len()).step_by(LANES) {
            let b = Block::load(z, y, None, start);
            // Padding lanes start from p = 0 and stay there: they add nothing.
            let mut pr = [0.0; LANES];
            pr[..b.lanes].fill(1.0);
            let mut pi = [0.0; LANES];
            let neg_y = b.y.map(|v| -v);
            for q in 0..=kmax {
                if want_mu {
                    fold_into(&mut mu_re[q], &pr);
                    fold_into(&mut mu_im[q], &pi);
                }
                // y conj(p) = (y p_re) + i (-y p_im).
                fold_product_into(&mut r_re[q], &b.y, &pr);
                fold_product_into(&mut r_im[q], &neg_y, &pi);
                advance(&mut pr, &mut pi, &b.zr, &b.zi);
            }
            for q in kmax + 1..nmu {
                fold_into(&mut mu_re[q], &pr);
                fold_into(&mut mu_im[q], &pi);
                advance(&mut pr, &mut pi, &b.zr, &b.zi);
            }
        }
        let mu = |acc: &[[f64; FOLD]]| if want_mu { unfold(acc) } else { vec![0.0; nq] };
        vec![mu(&mu_re), mu(&mu_im), unfold(&r_re), unfold(&r_im)]
    }
}

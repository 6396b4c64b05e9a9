//! Hot loops of the lab preprocessing (`python/bouc_wen_id/signal/`, issue #8): the harmonic
//! least squares behind the sine analysis, the steady segments and the synchronous average.
//!
//! A fit of `y` on `[1, cos k theta, sin k theta]`, `k = 1..K`, needs the Gram matrix of the basis
//! and its products with `y`. With `z_n = e^{i theta_n}` both follow from the complex moments
//! `mu_q = sum_n z_n^q` (`q = 0..2K`; the Gram matrix is Toeplitz-plus-Hankel in them) and
//! `r_q = sum_n y_n conj(z_n)^q` (`q = 0..K`), in one pass of the phasor recurrence
//! `z^(q+1) = z^q z`: O(n K) work instead of the O(n K^2) of forming the basis and its QR. The
//! NumPy reference of the same recurrence is `signal._harmonic_ls._moment_fit`; [`fit`] does the
//! rest of a fit (Gram matrix, conditioning check, Cholesky factor, solves, explicit residual) and
//! the Gauss-Newton frequency fit of `signal._sine._nls`, so that a fit is one call.
//!
//! The samples are processed in blocks of [`LANES`] held as separate real and imaginary arrays, so
//! that the recurrences of neighbouring samples (independent) fill the vector registers; [`wide`]
//! compiles the kernels for AVX2 when the CPU has it. Each sample's powers are formed as the NumPy
//! reference forms them (`p *= z`, complex multiply without fused operations); the phasors come
//! from [`sincos`] (within 2 ulp of `libm`) and the sums are taken in another order (rounding of
//! order `n eps` relative, far below the noise of any record).

pub mod fit;
pub mod sincos;
pub mod spectrum;
mod wide;
pub mod windows;

use wide::wide_fn;

use crate::error::{all_finite, CoreError, Result};

/// Samples advanced together through the phasor recurrence.
const LANES: usize = 16;
/// Partial sums kept per moment (one AVX2 register): the lanes are folded to these per harmonic
/// and to one number only at the end.
const FOLD: usize = 4;

fn check(theta: &[f64], y: &[f64], kmax: usize) -> Result<()> {
    all_finite("theta", theta)?;
    all_finite("y", y)?;
    if theta.len() != y.len() {
        return Err(CoreError::InvalidParameter(format!(
            "theta and y must have equal lengths, got {} and {}",
            theta.len(),
            y.len()
        )));
    }
    if kmax < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "kmax = {kmax} must be >= 1"
        )));
    }
    Ok(())
}

/// A fit on `kmax` harmonics has `2 kmax + 1` coefficients: `n` samples must hold at least that many
/// (the check also bounds the `(2 kmax + 1)^2` Gram matrix by the record's own size).
pub(crate) fn check_harmonics(n: usize, kmax: usize) -> Result<()> {
    if kmax.saturating_mul(2).saturating_add(1) > n {
        return Err(CoreError::InsufficientData(format!(
            "{kmax} harmonics need {} samples, the record holds {n}",
            kmax.saturating_mul(2).saturating_add(1)
        )));
    }
    Ok(())
}

fn check_coef(coef: &[f64], min_harmonics: usize) -> Result<()> {
    all_finite("coef", coef)?;
    if coef.len() % 2 == 0 || coef.len() < 2 * min_harmonics + 1 {
        return Err(CoreError::InvalidParameter(format!(
            "coef must hold 2K + 1 values [c, a_1, b_1, ...] with K >= {min_harmonics}, got {}",
            coef.len()
        )));
    }
    Ok(())
}

/// Where the phases of a record come from: given (`theta_n`), or `omega tau_n` (the frequency fit,
/// whose trial frequencies change them), or phasors already formed ([`Phasors::fill`]), which is
/// what the kernels read.
#[derive(Clone, Copy)]
pub(crate) enum Phases<'a> {
    Given(&'a [f64]),
    Scaled(f64, &'a [f64]),
    /// Phasors already formed: `(cos theta, sin theta)`, and the block template when every block
    /// of [`LANES`] from the first sample is the block's first phasor times it ([`Template`]).
    Cached(&'a [f64], &'a [f64], Option<&'a Template>),
}

/// `e^{i omega (tau_l - tau_0)}`, `l < LANES`: on a uniform time axis, the phasors of block `b` are
/// its first phasor times these ([`Phasors::fill`]).
#[derive(Clone, Copy)]
pub(crate) struct Template {
    re: [f64; LANES],
    im: [f64; LANES],
}

impl Phases<'_> {
    fn len(&self) -> usize {
        match self {
            Phases::Given(t) | Phases::Scaled(_, t) | Phases::Cached(t, _, _) => t.len(),
        }
    }

    /// `theta` itself, or `omega theta` when `omega` is given (`theta` then holds times).
    pub(crate) fn of(theta: &[f64], omega: Option<f64>) -> Phases<'_> {
        match omega {
            Some(w) => Phases::Scaled(w, theta),
            None => Phases::Given(theta),
        }
    }

    /// The samples `[from, to)` of the phases (a template stays when `from` starts a block).
    #[inline(always)]
    fn sub(&self, from: usize, to: usize) -> Self {
        match *self {
            Phases::Given(t) => Phases::Given(&t[from..to]),
            Phases::Scaled(w, t) => Phases::Scaled(w, &t[from..to]),
            Phases::Cached(c, s, tpl) => Phases::Cached(
                &c[from..to],
                &s[from..to],
                if from % LANES == 0 { tpl } else { None },
            ),
        }
    }
}

/// The phasors of a record formed once for the passes of a fit (moments, residual, Gauss-Newton
/// terms), in buffers that the caller reuses from fit to fit.
#[derive(Default)]
pub(crate) struct Phasors {
    re: Vec<f64>,
    im: Vec<f64>,
    theta: Vec<f64>,
    template: Option<Template>,
}

impl Phasors {
    /// Forms the phasors of `phases` and returns them (one vectorised [`sincos`] pass over the
    /// record: the loop the compiler vectorises best).
    #[inline(always)]
    pub(crate) fn fill(&mut self, phases: Phases<'_>) -> Phases<'_> {
        let n = phases.len();
        self.re.resize(n, 0.0);
        self.im.resize(n, 0.0);
        self.template = None;
        if let Phases::Scaled(w, t) = phases {
            if n >= 4 * LANES && uniform_blocks(t) {
                self.fill_uniform(w, t);
                return self.phases();
            }
            self.theta.clear();
            self.theta.extend(t.iter().map(|v| w * v));
        }
        let theta: &[f64] = match phases {
            Phases::Given(t) => t,
            Phases::Scaled(..) => &self.theta,
            Phases::Cached(c, s, tpl) => {
                self.re.copy_from_slice(c);
                self.im.copy_from_slice(s);
                self.template = tpl.copied();
                return self.phases();
            }
        };
        // Not split between threads: waking a second thread costs about what it would save here.
        sincos_wide(theta, &mut self.im, &mut self.re);
        self.phases()
    }

    /// The phasors of `omega tau` for times `tau` whose blocks of [`LANES`] are spaced alike
    /// ([`uniform_blocks`]): `e^{i omega tau_b}` at each block's first sample (vectorised
    /// [`sincos`], one in [`LANES`]) times the block template `e^{i omega (tau_l - tau_0)}`. The
    /// template's phase differs from each block's own by at most `omega` times the spacing
    /// tolerance (a few ulp of the times: below 1e-12 rad over any record), as small as the
    /// rounding of `omega tau` itself.
    #[inline(always)]
    fn fill_uniform(&mut self, omega: f64, tau: &[f64]) {
        let n = tau.len();
        let (mut tr, mut ti) = ([0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            (ti[l], tr[l]) = sincos::sincos(omega * (tau[l] - tau[0]));
        }
        self.theta.clear();
        self.theta
            .extend(tau.iter().step_by(LANES).map(|v| omega * v));
        let nb = self.theta.len();
        let (mut bs, mut bc) = (vec![0.0; nb], vec![0.0; nb]);
        sincos::sincos_into(&self.theta, &mut bs, &mut bc);
        for (b, (zr, zi)) in bc.iter().zip(&bs).enumerate() {
            let start = b * LANES;
            let lanes = LANES.min(n - start);
            let (re, im) = (
                &mut self.re[start..start + lanes],
                &mut self.im[start..start + lanes],
            );
            for l in 0..lanes {
                re[l] = zr * tr[l] - zi * ti[l];
                im[l] = zr * ti[l] + zi * tr[l];
            }
        }
        self.template = Some(Template { re: tr, im: ti });
    }

    /// `f` with this thread's two phasor buffers: fresh record-sized buffers at every call cost
    /// more in page faults than the passes over them (issue #8), so they are kept and reused.
    #[inline(always)]
    pub(crate) fn with<R>(f: impl FnOnce(&mut Phasors, &mut Phasors) -> R) -> R {
        thread_local! {
            static BUFFERS: std::cell::RefCell<(Phasors, Phasors)> =
                std::cell::RefCell::new((Phasors::default(), Phasors::default()));
        }
        BUFFERS.with(|cell| match cell.try_borrow_mut() {
            Ok(mut bufs) => {
                let (a, b) = &mut *bufs;
                f(a, b)
            }
            // Re-entered (not done by the kernels): fresh buffers.
            Err(_) => f(&mut Phasors::default(), &mut Phasors::default()),
        })
    }

    /// The phasors formed by the last [`Phasors::fill`].
    pub(crate) fn phases(&self) -> Phases<'_> {
        Phases::Cached(&self.re, &self.im, self.template.as_ref())
    }
}

/// Whether every block of [`LANES`] samples of `tau` is spaced as the first one, to within 4 ulp
/// of the largest time: `|(tau_{b+l} - tau_b) - (tau_l - tau_0)| <= 4 eps max|tau|` (uniform
/// sampling, as from `np.arange`; a jittered time axis fails and gets a [`sincos`] per sample).
#[inline(always)]
fn uniform_blocks(tau: &[f64]) -> bool {
    // Comparisons ORed lane by lane (no early exit, no NaN-aware max): the scan vectorises.
    let mut big = [0.0f64; LANES];
    for block in tau.chunks_exact(LANES) {
        for l in 0..LANES {
            let a = block[l].abs();
            big[l] = if a > big[l] { a } else { big[l] };
        }
    }
    let big = tau[tau.len() / LANES * LANES..]
        .iter()
        .chain(&big)
        .fold(0.0f64, |m, v| if v.abs() > m { v.abs() } else { m });
    let tol = 4.0 * f64::EPSILON * big;
    let mut step = [0.0; LANES];
    for l in 0..LANES {
        step[l] = tau[l] - tau[0];
    }
    let mut bad = [false; LANES];
    for block in tau.chunks_exact(LANES) {
        for l in 0..LANES {
            bad[l] |= ((block[l] - block[0]) - step[l]).abs() > tol;
        }
    }
    let rest = tau.chunks_exact(LANES).remainder();
    let tail_bad = rest
        .iter()
        .enumerate()
        .any(|(l, v)| ((v - rest[0]) - step[l]).abs() > tol);
    !(tail_bad || bad.iter().any(|&b| b))
}

wide_fn! {
    /// [`sincos::sincos_into`] compiled for the machine's vector width.
    fn sincos_wide(x: &[f64], out_sin: &mut [f64], out_cos: &mut [f64]) -> () {
        sincos::sincos_into(x, out_sin, out_cos)
    }
}

/// One block of at most [`LANES`] samples, zero-padded: its phasors (padding lanes `1 + 0i`), the
/// record's values (and times) there, and how many lanes are real.
struct Block {
    zr: [f64; LANES],
    zi: [f64; LANES],
    y: [f64; LANES],
    tau: [f64; LANES],
    lanes: usize,
}

impl Block {
    #[inline(always)]
    fn load(phases: Phases<'_>, y: &[f64], tau: Option<&[f64]>, start: usize) -> Self {
        let lanes = LANES.min(y.len() - start);
        let Phases::Cached(c, si, _) = phases.sub(start, start + lanes) else {
            unreachable!("the kernels read phasors formed by Phasors::fill")
        };
        let full = |v: &[f64]| -> [f64; LANES] { v.try_into().expect("a whole block") };
        if lanes == LANES {
            // Whole blocks (all but the last): fixed-size copies, which compile to vector moves.
            return Block {
                zr: full(c),
                zi: full(si),
                y: full(&y[start..start + LANES]),
                tau: tau.map_or([0.0; LANES], |t| full(&t[start..start + LANES])),
                lanes,
            };
        }
        // Padding lanes: 1 + 0i.
        let (mut zr, mut zi) = ([1.0; LANES], [0.0; LANES]);
        zr[..lanes].copy_from_slice(c);
        zi[..lanes].copy_from_slice(si);
        let mut b = Block {
            zr,
            zi,
            y: [0.0; LANES],
            tau: [0.0; LANES],
            lanes,
        };
        b.y[..lanes].copy_from_slice(&y[start..start + lanes]);
        if let Some(t) = tau {
            b.tau[..lanes].copy_from_slice(&t[start..start + lanes]);
        }
        b
    }
}

/// `p <- p z` lane by lane, as NumPy multiplies complex numbers: `(ac - bd) + i(ad + bc)`.
#[inline(always)]
fn advance(pr: &mut [f64; LANES], pi: &mut [f64; LANES], zr: &[f64; LANES], zi: &[f64; LANES]) {
    for l in 0..LANES {
        let (a, b) = (pr[l], pi[l]);
        pr[l] = a * zr[l] - b * zi[l];
        pi[l] = a * zi[l] + b * zr[l];
    }
}

/// `acc[f] += sum of lanes f, f + FOLD, f + 2 FOLD, ...` of `v`.
#[inline(always)]
fn fold_into(acc: &mut [f64; FOLD], v: &[f64; LANES]) {
    let mut s = [0.0; FOLD];
    for c in v.chunks_exact(FOLD) {
        for f in 0..FOLD {
            s[f] += c[f];
        }
    }
    for f in 0..FOLD {
        acc[f] += s[f];
    }
}

/// `acc[f] += sum of lanes f, f + FOLD, ... of w * v`.
#[inline(always)]
fn fold_product_into(acc: &mut [f64; FOLD], w: &[f64; LANES], v: &[f64; LANES]) {
    let mut prod = [0.0; LANES];
    for l in 0..LANES {
        prod[l] = w[l] * v[l];
    }
    fold_into(acc, &prod);
}

fn unfold(acc: &[[f64; FOLD]]) -> Vec<f64> {
    acc.iter().map(|a| a.iter().sum()).collect()
}

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
fn templated_mu(re: &[f64], im: &[f64], t: &Template, kmax: usize) -> (Vec<f64>, Vec<f64>) {
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
const SPLIT_WORK: usize = 1 << 20;

/// Where a record of `n` samples is split in two: the middle, rounded to whole blocks.
fn split_point(n: usize) -> usize {
    (n / 2).div_ceil(LANES) * LANES
}

wide_fn! {
    /// `[mu_re, mu_im, r_re, r_im]` of [`moments_of`] over one part of a record (the `mu` all
    /// zero unless `want_mu`).
    fn moments_part(z: Phases<'_>, y: &[f64], kmax: usize, want_mu: bool) -> Vec<Vec<f64>> {
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

/// The series `coef[0] + sum_k coef[2k-1] Re p_k + coef[2k] Im p_k` of one block, `p_k = z^k`.
#[inline(always)]
fn block_series(b: &Block, coef: &[f64]) -> [f64; LANES] {
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
    fn rss_part(z: Phases<'_>, y: &[f64], coef: &[f64]) -> f64 {
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

/// Moments of the harmonic basis at the phases `theta` (rad, length n) against `y` (length n):
/// `mu_q = sum_n e^{i q theta_n}`, `q = 0..=2 kmax`, and `r_q = sum_n y_n e^{-i q theta_n}`,
/// `q = 0..=kmax`, each as `(real parts, imaginary parts)`.
///
/// Errors: non-finite input, unequal lengths, `kmax < 1`, fewer samples than `2 kmax + 1`.
#[allow(clippy::type_complexity)]
pub fn harmonic_moments(
    theta: &[f64],
    y: &[f64],
    kmax: usize,
) -> Result<((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>))> {
    check(theta, y, kmax)?;
    check_harmonics(theta.len(), kmax)?;
    Ok(Phasors::with(|z, _| moments_wide(theta, y, kmax, z)))
}

/// `(mu, r)` moments as (real, imaginary) parts.
type Moments = ((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>));

wide_fn! {
    fn moments_wide(theta: &[f64], y: &[f64], kmax: usize, z: &mut Phasors) -> Moments {
        moments_of(z.fill(Phases::Given(theta)), y, kmax)
    }
}

/// The harmonic series `coef[0] + sum_k coef[2k-1] cos(k theta_n) + coef[2k] sin(k theta_n)` at
/// every phase (length n), by the same phasor recurrence; `coef` has length `2K + 1`, `K >= 0`.
///
/// Errors: non-finite input, an even `coef` length.
pub fn harmonic_series(theta: &[f64], coef: &[f64]) -> Result<Vec<f64>> {
    all_finite("theta", theta)?;
    check_coef(coef, 0)?;
    Ok(Phasors::with(|z, _| series_wide(theta, coef, z)))
}

wide_fn! {
    fn series_wide(theta: &[f64], coef: &[f64], buf: &mut Phasors) -> Vec<f64> {
        let mut out = vec![0.0; theta.len()];
        let z = buf.fill(Phases::Given(theta));
        for start in (0..theta.len()).step_by(LANES) {
            let b = Block::load(z, theta, None, start);
            let s = block_series(&b, coef);
            out[start..start + b.lanes].copy_from_slice(&s[..b.lanes]);
        }
        out
    }
}

/// Residual sum of squares `sum_n (y_n - series(theta_n))^2` (units of `y` squared) of the harmonic
/// series `coef` (as [`harmonic_series`]) against `y` (length n), without the n-vector of the series:
/// the fast path's explicit residual needs no BLAS call (a threaded `ddot` on a long vector costs
/// milliseconds on a loaded machine, more than the fit).
///
/// Errors: non-finite input, unequal lengths, an even `coef` length.
pub fn harmonic_rss(theta: &[f64], y: &[f64], coef: &[f64]) -> Result<f64> {
    harmonic_rss_at(theta, None, y, coef)
}

/// [`harmonic_rss`] at the phases `theta`, or at `omega tau` when `omega` (rad/s) is given and
/// `theta` holds the times `tau` (s): no wrapped phase array is formed (the reduction of [`sincos`]
/// is exact over a record's phases).
///
/// Errors: as [`harmonic_rss`], and a non-finite `omega`.
pub fn harmonic_rss_at(theta: &[f64], omega: Option<f64>, y: &[f64], coef: &[f64]) -> Result<f64> {
    check(theta, y, 1)?;
    check_coef(coef, 0)?;
    check_omega(omega)?;
    Ok(Phasors::with(|z, _| rss_wide(theta, omega, y, coef, z)))
}

/// `a` finite and holding an `m x m` matrix (`m >= 1`).
pub(crate) fn check_square(name: &str, a: &[f64], m: usize) -> Result<()> {
    all_finite(name, a)?;
    if a.len() != m * m || m == 0 {
        return Err(CoreError::InvalidParameter(format!(
            "{name} must hold m * m = {} values (m >= 1), got {}",
            m * m,
            a.len()
        )));
    }
    Ok(())
}

/// `omega`, when given, finite.
pub(crate) fn check_omega(omega: Option<f64>) -> Result<()> {
    match omega {
        Some(w) if !w.is_finite() => {
            Err(CoreError::NonFinite(format!("omega = {w} is not finite")))
        }
        _ => Ok(()),
    }
}

wide_fn! {
    fn rss_wide(theta: &[f64], omega: Option<f64>, y: &[f64], coef: &[f64], z: &mut Phasors) -> f64 {
        rss_of(z.fill(Phases::of(theta, omega)), y, coef)
    }
}

/// Upper Cholesky factor `R` (`R^T R = G`, row-major `m x m`, zeros below the diagonal) of the
/// symmetric positive definite Gram matrix `gram` (row-major `m x m`, only its lower triangle read),
/// as `numpy.linalg.cholesky(gram).T`. The synchronous average's Gram matrix has `m = 2K + 1` up to
/// 401; LAPACK through a threaded OpenBLAS wakes its threads for it, which on a loaded 2-core machine
/// cost hundreds of milliseconds per call (issue #8), against a few here (dot-product form, rows
/// contiguous).
///
/// Errors: non-finite input, `gram.len() != m * m`, a matrix that is not positive definite.
pub fn cholesky_upper(gram: &[f64], m: usize) -> Result<Vec<f64>> {
    check_square("gram", gram, m)?;
    cholesky_wide(gram, m).map_err(|(i, s)| {
        CoreError::InvalidParameter(format!(
            "the Gram matrix is not positive definite (pivot {i}: {s:e})"
        ))
    })
}

wide_fn! {
    fn cholesky_wide(gram: &[f64], m: usize) -> std::result::Result<Vec<f64>, (usize, f64)> {
        cholesky_of(gram, m)
    }
}

/// The factor of [`cholesky_upper`], or the failing pivot `(index, value)`.
#[inline(always)]
pub(crate) fn cholesky_of(gram: &[f64], m: usize) -> std::result::Result<Vec<f64>, (usize, f64)> {
    // Lower factor L, row-major with rows padded to whole chunks of CHOL_LANES and zero-filled:
    // L[i][j] = (G[i][j] - L[i][..j] . L[j][..j]) / L[j][j]. Row j is zero beyond its diagonal and
    // L[i][j] is still zero when its own dot product runs, so every dot product can run to the
    // next whole chunk without a scalar tail (the same sum: the extra terms are exact zeros).
    const CHOL_LANES: usize = 8;
    let stride = m.div_ceil(CHOL_LANES) * CHOL_LANES;
    let mut l = vec![0.0; m * stride];
    let dot = |l: &[f64], i: usize, j: usize| -> f64 {
        let len = j.div_ceil(CHOL_LANES) * CHOL_LANES;
        let (ri, rj) = (
            &l[i * stride..i * stride + len],
            &l[j * stride..j * stride + len],
        );
        let mut acc = [0.0; CHOL_LANES];
        for (a, b) in ri.chunks_exact(CHOL_LANES).zip(rj.chunks_exact(CHOL_LANES)) {
            for k in 0..CHOL_LANES {
                acc[k] += a[k] * b[k];
            }
        }
        acc.iter().sum::<f64>()
    };
    // Rows in groups of CHOL_ROWS: each earlier row j is read once per group (not once per row),
    // which keeps the factor of the synchronous average (m = 2K + 1 up to 401, over 1 MB) from
    // being streamed m times through the cache.
    const CHOL_ROWS: usize = 8;
    for i0 in (0..m).step_by(CHOL_ROWS) {
        let i1 = (i0 + CHOL_ROWS).min(m);
        for j in 0..i0 {
            let mut sums = [0.0; CHOL_ROWS];
            for (i, sum) in (i0..i1).zip(sums.iter_mut()) {
                *sum = dot(&l, i, j);
            }
            let d = l[j * stride + j];
            for (i, sum) in (i0..i1).zip(sums) {
                l[i * stride + j] = (gram[i * m + j] - sum) / d;
            }
        }
        for i in i0..i1 {
            for j in i0..=i {
                let s = gram[i * m + j] - dot(&l, i, j);
                if i == j {
                    if s.is_nan() || s <= 0.0 {
                        return Err((i, s));
                    }
                    l[i * stride + i] = s.sqrt();
                } else {
                    l[i * stride + j] = s / l[j * stride + j];
                }
            }
        }
    }
    let mut r = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..=i {
            r[j * m + i] = l[i * stride + j];
        }
    }
    Ok(r)
}

/// Gauss-Newton terms of the frequency fit (variable projection, `signal._sine._nls`) at the phases
/// `theta = omega tau` (rad), the times `tau` (s), the record `x` and the harmonic coefficients
/// `coef = [c, a_1, b_1, ...]` (length `2K + 1`, `K >= 1`), in one pass without forming the basis:
/// with the residual `r = x - X coef` and `d = d(X coef)/d omega = tau sum_k k (b_k cos k theta -
/// a_k sin k theta)`, returns `(r.r, r.d, d.d, X^T d)` (`X^T d` of length `2K + 1`, ordered as
/// `coef`). The NumPy reference forms `X` (`_harmonic_ls.harmonic_basis`) and `d`
/// (`_sine._omega_column`) explicitly.
///
/// Errors: non-finite input, unequal lengths, an even `coef` length or `K = 0`.
pub fn harmonic_gauss_newton(
    theta: &[f64],
    tau: &[f64],
    x: &[f64],
    coef: &[f64],
) -> Result<(f64, f64, f64, Vec<f64>)> {
    check(theta, x, 1)?;
    all_finite("tau", tau)?;
    if tau.len() != theta.len() {
        return Err(CoreError::InvalidParameter(format!(
            "theta and tau must have equal lengths, got {} and {}",
            theta.len(),
            tau.len()
        )));
    }
    check_coef(coef, 1)?;
    Ok(Phasors::with(|z, _| {
        gauss_newton_wide(theta, tau, x, coef, z)
    }))
}

wide_fn! {
    fn gauss_newton_wide(
        theta: &[f64],
        tau: &[f64],
        x: &[f64],
        coef: &[f64],
        z: &mut Phasors,
    ) -> (f64, f64, f64, Vec<f64>) {
        gauss_newton_of(z.fill(Phases::Given(theta)), tau, x, coef)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_times_get_block_templates_and_jittered_ones_do_not() {
        let n = 1000;
        let tau: Vec<f64> = (0..n).map(|i| i as f64 * 0.02 - 10.0).collect();
        assert!(uniform_blocks(&tau));
        let omega = 3.7;
        let mut z = Phasors::default();
        let Phases::Cached(re, im, _) = z.fill(Phases::Scaled(omega, &tau)) else {
            unreachable!()
        };
        for (i, t) in tau.iter().enumerate() {
            let (s, c) = (omega * t).sin_cos();
            assert!(
                (re[i] - c).abs() < 1e-13 && (im[i] - s).abs() < 1e-13,
                "sample {i}"
            );
        }
        // A time axis written with 6 decimals (1e-7 s jitter) is not uniform to a few ulp.
        let mut j2: Vec<f64> = tau
            .iter()
            .map(|t| (t * 1e6 + 0.3).round() / 1e6 + 1e-7)
            .collect();
        j2[517] += 3e-7;
        assert!(!uniform_blocks(&j2));
        let Phases::Cached(re, im, _) = z.fill(Phases::Scaled(omega, &j2)) else {
            unreachable!()
        };
        for (i, t) in j2.iter().enumerate() {
            let (s, c) = (omega * t).sin_cos();
            assert!(
                (re[i] - c).abs() < 1e-15 && (im[i] - s).abs() < 1e-15,
                "sample {i}"
            );
        }
    }

    #[test]
    fn templated_moments_match_the_per_sample_sums() {
        for n in [64, 1003, 4099] {
            let tau: Vec<f64> = (0..n).map(|i| i as f64 * 0.01 - 3.0).collect();
            let y: Vec<f64> = tau.iter().map(|t| (7.0 * t).cos() + 0.1 * t).collect();
            let mut z = Phasors::default();
            let phases = z.fill(Phases::Scaled(5.3, &tau));
            let Phases::Cached(re, im, Some(_)) = phases else {
                panic!("a uniform axis gets a template")
            };
            let k = 40;
            let ((mr, mi), (rr, ri)) = moments_of(phases, &y, k);
            let ((er, ei), (sr, si)) = moments_of(Phases::Cached(re, im, None), &y, k);
            for q in 0..=2 * k {
                assert!(
                    (mr[q] - er[q]).abs() < 1e-11 * n as f64
                        && (mi[q] - ei[q]).abs() < 1e-11 * n as f64,
                    "n = {n}, q = {q}"
                );
            }
            assert_eq!((rr, ri), (sr, si));
        }
    }

    #[test]
    fn moments_match_direct_sums() {
        let n = 37; // not a multiple of LANES: the last block is partial
        let theta: Vec<f64> = (0..n).map(|i| 0.37 * i as f64 + 0.1).collect();
        let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.2).collect();
        let k = 5;
        let ((mr, mi), (rr, ri)) = harmonic_moments(&theta, &y, k).unwrap();
        for q in 0..=2 * k {
            let (er, ei): (f64, f64) = theta.iter().fold((0.0, 0.0), |acc, t| {
                (acc.0 + (q as f64 * t).cos(), acc.1 + (q as f64 * t).sin())
            });
            assert!(
                (mr[q] - er).abs() < 1e-12 && (mi[q] - ei).abs() < 1e-12,
                "q = {q}"
            );
        }
        for q in 0..=k {
            let (er, ei) = theta.iter().zip(&y).fold((0.0, 0.0), |acc, (t, v)| {
                (
                    acc.0 + v * (q as f64 * t).cos(),
                    acc.1 - v * (q as f64 * t).sin(),
                )
            });
            assert!(
                (rr[q] - er).abs() < 1e-12 && (ri[q] - ei).abs() < 1e-12,
                "q = {q}"
            );
        }
    }

    #[test]
    fn series_matches_direct_sum_and_validates() {
        let theta: Vec<f64> = (0..21).map(|i| 0.3 * i as f64).collect();
        let coef = [0.5, 1.0, -0.3, 0.2, 0.7, -0.1, 0.05];
        let s = harmonic_series(&theta, &coef).unwrap();
        for (t, v) in theta.iter().zip(&s) {
            let mut e = coef[0];
            for k in 1..=3 {
                e += coef[2 * k - 1] * (k as f64 * t).cos() + coef[2 * k] * (k as f64 * t).sin();
            }
            assert!((v - e).abs() < 1e-13);
        }
        assert!(harmonic_series(&theta, &coef[..6]).is_err());
        assert!(harmonic_moments(&theta, &theta[..3], 2).is_err());
        assert!(harmonic_moments(&theta, &theta, 0).is_err());
        let bad = [f64::NAN, 1.0];
        assert!(matches!(
            harmonic_moments(&bad, &bad, 1),
            Err(CoreError::NonFinite(_))
        ));
    }

    #[test]
    fn gauss_newton_terms_match_direct_sums_and_validate() {
        let n = 29; // a partial last block
        let tau: Vec<f64> = (0..n).map(|i| 0.01 * i as f64 - 0.1).collect();
        let omega = 7.3;
        let theta: Vec<f64> = tau.iter().map(|t| omega * t).collect();
        let x: Vec<f64> = theta.iter().map(|t| 1.2 * (t + 0.3).sin() + 0.1).collect();
        let coef = [0.05, 0.3, 1.1, -0.02, 0.04];
        let (rr, rd, dd, xtd) = harmonic_gauss_newton(&theta, &tau, &x, &coef).unwrap();
        let (mut err, mut erd, mut edd) = (0.0, 0.0, 0.0);
        let mut extd = [0.0; 5];
        for i in 0..n {
            let t = theta[i];
            let mut f = coef[0];
            let mut sl = 0.0;
            for k in 1..=2 {
                let kf = k as f64;
                f += coef[2 * k - 1] * (kf * t).cos() + coef[2 * k] * (kf * t).sin();
                sl += kf * (coef[2 * k] * (kf * t).cos() - coef[2 * k - 1] * (kf * t).sin());
            }
            let d = tau[i] * sl;
            let r = x[i] - f;
            err += r * r;
            erd += r * d;
            edd += d * d;
            extd[0] += d;
            for k in 1..=2 {
                extd[2 * k - 1] += d * (k as f64 * t).cos();
                extd[2 * k] += d * (k as f64 * t).sin();
            }
        }
        assert!((rr - err).abs() < 1e-12 && (rd - erd).abs() < 1e-12 && (dd - edd).abs() < 1e-12);
        for (a, b) in xtd.iter().zip(&extd) {
            assert!((a - b).abs() < 1e-12);
        }
        assert!(harmonic_gauss_newton(&theta, &tau, &x, &coef[..4]).is_err());
        assert!(harmonic_gauss_newton(&theta, &tau, &x, &coef[..1]).is_err());
        assert!(harmonic_gauss_newton(&theta, &tau[..3], &x, &coef).is_err());
    }

    #[test]
    fn rss_matches_the_explicit_residual() {
        let theta: Vec<f64> = (0..45).map(|i| 0.21 * i as f64).collect();
        let y: Vec<f64> = theta.iter().map(|t| (t + 0.2).cos() + 0.1).collect();
        let coef = [0.1, 0.9, -0.2, 0.05, 0.01];
        let s = harmonic_series(&theta, &coef).unwrap();
        let e: f64 = y.iter().zip(&s).map(|(a, b)| (a - b) * (a - b)).sum();
        let got = harmonic_rss(&theta, &y, &coef).unwrap();
        assert!((got - e).abs() <= 1e-14 * e.max(1.0));
        assert!(harmonic_rss(&theta, &y[..4], &coef).is_err());
        assert!(harmonic_rss(&theta, &y, &coef[..2]).is_err());
    }

    #[test]
    fn cholesky_reproduces_the_matrix_and_refuses_indefinite_ones() {
        let m = 11; // not a multiple of LANES
        let a: Vec<f64> = (0..m * m)
            .map(|i| ((i * 7 % 13) as f64 - 6.0) / 10.0)
            .collect();
        let mut g = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                g[i * m + j] = (0..m).map(|k| a[k * m + i] * a[k * m + j]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        let r = cholesky_upper(&g, m).unwrap();
        for i in 0..m {
            for j in 0..m {
                let e: f64 = (0..m).map(|k| r[k * m + i] * r[k * m + j]).sum();
                assert!((e - g[i * m + j]).abs() < 1e-12, "({i}, {j})");
                if j < i {
                    assert_eq!(r[i * m + j], 0.0);
                }
            }
        }
        let mut bad = g.clone();
        bad[0] = -1.0;
        assert!(cholesky_upper(&bad, m).is_err());
        assert!(cholesky_upper(&g[..10], m).is_err());
    }
}

//! The record's phasors `e^{i theta_n}` and the lane blocks the lab kernels read them in: where the
//! phases come from ([`Phases`]), the phasors formed once per fit ([`Phasors`], with the block template
//! of a uniform time axis), one zero-padded block of [`LANES`] samples ([`Block`]) and the lane-wise
//! complex products and partial sums every kernel is made of.

use super::sincos;
use super::wide::wide_fn;

/// Samples advanced together through the phasor recurrence.
pub(super) const LANES: usize = 16;
/// Partial sums kept per moment (one AVX2 register): the lanes are folded to these per harmonic
/// and to one number only at the end.
pub(super) const FOLD: usize = 4;

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
    pub(super) re: [f64; LANES],
    pub(super) im: [f64; LANES],
}

impl Phases<'_> {
    pub(super) fn len(&self) -> usize {
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
    pub(super) fn sub(&self, from: usize, to: usize) -> Self {
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
    pub(super) fn fill_uniform(&mut self, omega: f64, tau: &[f64]) {
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
pub(super) fn uniform_blocks(tau: &[f64]) -> bool {
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
    pub(super) fn sincos_wide(x: &[f64], out_sin: &mut [f64], out_cos: &mut [f64]) -> () {
        sincos::sincos_into(x, out_sin, out_cos)
    }
}

/// One block of at most [`LANES`] samples, zero-padded: its phasors (padding lanes `1 + 0i`), the
/// record's values (and times) there, and how many lanes are real.
pub(super) struct Block {
    pub(super) zr: [f64; LANES],
    pub(super) zi: [f64; LANES],
    pub(super) y: [f64; LANES],
    pub(super) tau: [f64; LANES],
    pub(super) lanes: usize,
}

impl Block {
    #[inline(always)]
    pub(super) fn load(phases: Phases<'_>, y: &[f64], tau: Option<&[f64]>, start: usize) -> Self {
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
pub(super) fn advance(
    pr: &mut [f64; LANES],
    pi: &mut [f64; LANES],
    zr: &[f64; LANES],
    zi: &[f64; LANES],
) {
    for l in 0..LANES {
        let (a, b) = (pr[l], pi[l]);
        pr[l] = a * zr[l] - b * zi[l];
        pi[l] = a * zi[l] + b * zr[l];
    }
}

/// `acc[f] += sum of lanes f, f + FOLD, f + 2 FOLD, ...` of `v`.
#[inline(always)]
pub(super) fn fold_into(acc: &mut [f64; FOLD], v: &[f64; LANES]) {
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
pub(super) fn fold_product_into(acc: &mut [f64; FOLD], w: &[f64; LANES], v: &[f64; LANES]) {
    let mut prod = [0.0; LANES];
    for l in 0..LANES {
        prod[l] = w[l] * v[l];
    }
    fold_into(acc, &prod);
}

pub(super) fn unfold(acc: &[[f64; FOLD]]) -> Vec<f64> {
    acc.iter().map(|a| a.iter().sum()).collect()
}

//! Linear part of the Wiener model, `x = g * u` with `G(s) = e^{-tau s} num(s)/den(s)` (1a) of the
//! seed paper: validation (proper, Routh-Hurwitz stable), controllable canonical realisation and
//! frequency response. See `docs/design.md` §1.
//!
//! Coefficients are ordered highest power of `s` first (the scipy.signal convention).
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use nalgebra::Complex;

use crate::error::{all_finite, finite, CoreError, Result};

/// A validated, proper, asymptotically stable transfer function with an input delay.
#[derive(Debug, Clone, PartialEq)]
pub struct TransferFunction {
    num: Vec<f64>,
    den: Vec<f64>,
    delay: f64,
}

/// Controllable canonical form `xsdot = A xs + B v`, `x = C xs + D v` of a [`TransferFunction`].
///
/// `A` is the companion matrix with first row `-a[0..n]` and ones on the subdiagonal, `B = e_1`:
/// it is kept as the vector `a`, so that `A xs` costs O(n).
#[derive(Debug, Clone, PartialEq)]
pub struct Companion {
    /// Monic denominator coefficients `a_1..a_n` (length n): `A[0, j] = -a[j]`.
    pub a: Vec<f64>,
    /// Output row `C` (length n).
    pub c: Vec<f64>,
    /// Feed-through `D`.
    pub d: f64,
}

impl Companion {
    /// State dimension n (0 for a static gain).
    pub fn order(&self) -> usize {
        self.a.len()
    }

    /// `xsdot = A xs + B v` into `dxs`: `xs`, `dxs` of length n (state units, per second for
    /// `dxs`), `v` the (delayed) input. O(n) thanks to the companion structure.
    ///
    /// # Panics
    /// If `xs` or `dxs` is shorter than the order n.
    #[inline(always)]
    pub fn state_derivative(&self, xs: &[f64], v: f64, dxs: &mut [f64]) {
        let n = self.a.len();
        if n == 0 {
            return;
        }
        let (xs, dxs) = (&xs[..n], &mut dxs[..n]);
        let mut acc = 0.0;
        for (ai, xi) in self.a.iter().zip(xs) {
            acc += ai * xi;
        }
        dxs[0] = -acc + v;
        dxs[1..].copy_from_slice(&xs[..n - 1]);
    }

    /// `C y` for a state-sized vector `y` (length n): with `y = xs` the strictly proper part of
    /// `x`, with `y = xsdot` that of `xdot`.
    #[inline(always)]
    pub fn output_row(&self, y: &[f64]) -> f64 {
        let mut acc = 0.0;
        for (ci, yi) in self.c.iter().zip(y) {
            acc += ci * yi;
        }
        acc
    }
}

/// Routh-Hurwitz test: `true` when every root of `den` (highest power first) has a strictly
/// negative real part.
///
/// After normalising `den[0] = 1`, every entry of the Routh array's first column must be strictly
/// positive; a zero entry means "not asymptotically stable" and is rejected. A constant (degree 0)
/// is stable. Non-finite coefficients, or `den[0] == 0`, give `false`.
pub fn routh_hurwitz_stable(den: &[f64]) -> bool {
    let Some(&lead) = den.first() else {
        return false;
    };
    if lead == 0.0 || !lead.is_finite() {
        return false;
    }
    let a: Vec<f64> = den.iter().map(|v| v / lead).collect();
    let n = a.len() - 1;
    if n == 0 {
        return true;
    }
    // Rows of the Routh array, all padded to the width of the first one.
    let width = a.len().div_ceil(2);
    let mut prev: Vec<f64> = a.iter().step_by(2).copied().collect();
    let mut cur: Vec<f64> = a.iter().skip(1).step_by(2).copied().collect();
    prev.resize(width, 0.0);
    cur.resize(width, 0.0);
    let mut firsts = vec![prev[0], cur[0]];
    for _ in 0..n - 1 {
        // Checked before dividing by it: a zero pivot already decides "not stable".
        if cur[0] <= 0.0 {
            return false;
        }
        let mut next = vec![0.0; width];
        for j in 0..width - 1 {
            next[j] = (cur[0] * prev[j + 1] - prev[0] * cur[j + 1]) / cur[0];
        }
        prev = std::mem::replace(&mut cur, next);
        firsts.push(cur[0]);
    }
    // `> 0.0` is false for NaN, so a degenerate array is never called stable.
    firsts.iter().all(|&f| f > 0.0)
}

impl TransferFunction {
    /// Validates `G(s) = e^{-delay s} num(s)/den(s)`.
    ///
    /// `num`, `den`: polynomial coefficients, highest power first (any length >= 1 for `den`;
    /// leading zeros of `num` are stripped, an all-zero or empty `num` is the zero gain).
    /// `delay`: input delay tau in seconds, `>= 0`.
    ///
    /// Errors: [`CoreError::NonFinite`] for a NaN/inf coefficient or delay,
    /// [`CoreError::InvalidParameter`] for a negative delay, [`CoreError::Improper`] when `den` is
    /// empty, `den[0] == 0` or `deg num > deg den`, [`CoreError::Unstable`] when Routh-Hurwitz
    /// finds a root with `Re >= 0`.
    pub fn new(num: &[f64], den: &[f64], delay: f64) -> Result<Self> {
        all_finite("num", num)?;
        all_finite("den", den)?;
        let delay = finite("delay", delay)?;
        if delay < 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "delay = {delay} s is negative; a pure delay must be >= 0"
            )));
        }
        if den.first().is_none_or(|&d| d == 0.0) {
            return Err(CoreError::Improper(
                "den must start with a non-zero coefficient (highest power of s first); \
                 strip its leading zeros"
                    .into(),
            ));
        }
        let num: Vec<f64> = match num.iter().position(|&b| b != 0.0) {
            Some(first) => num[first..].to_vec(),
            None => vec![0.0],
        };
        if num.len() > den.len() {
            return Err(CoreError::Improper(format!(
                "G(s) is improper: numerator degree {} > denominator degree {}; a physical linear \
                 part must be proper",
                num.len() - 1,
                den.len() - 1
            )));
        }
        if !routh_hurwitz_stable(den) {
            return Err(CoreError::Unstable(format!(
                "G(s) is not asymptotically stable: den = {den:?} has a root with Re >= 0 \
                 (Routh-Hurwitz); the sine steady state the method relies on does not exist"
            )));
        }
        Ok(Self {
            num,
            den: den.to_vec(),
            delay,
        })
    }

    /// Numerator coefficients (leading zeros stripped), highest power first.
    pub fn num(&self) -> &[f64] {
        &self.num
    }

    /// Denominator coefficients, highest power first; `den[0] != 0`.
    pub fn den(&self) -> &[f64] {
        &self.den
    }

    /// Input delay tau (s).
    pub fn delay(&self) -> f64 {
        self.delay
    }

    /// Order n = deg den (number of states of the realisation).
    pub fn order(&self) -> usize {
        self.den.len() - 1
    }

    /// Controllable canonical realisation: `a = den/den[0]`, `b = num/den[0]` left-padded to
    /// length n+1; `A[0, j] = -a[j+1]`, `A[i, i-1] = 1`, `B = e_1`, `C[j] = b[j+1] - b[0] a[j+1]`,
    /// `D = b[0]`. Order 0 is a static gain (`a`, `c` empty).
    pub fn realize(&self) -> Companion {
        let n = self.order();
        let lead = self.den[0];
        let an: Vec<f64> = self.den.iter().map(|v| v / lead).collect();
        let mut bn = vec![0.0; n + 1 - self.num.len()];
        bn.extend(self.num.iter().map(|v| v / lead));
        let d = bn[0];
        let c = (1..=n).map(|j| bn[j] - d * an[j]).collect();
        Companion {
            a: an[1..].to_vec(),
            c,
            d,
        }
    }

    /// Frequency response `G(j omega) = e^{-j omega tau} num(j omega)/den(j omega)` as `(re, im)`.
    ///
    /// `omega` in rad/s. A non-finite `omega` gives NaN parts.
    pub fn freq_response(&self, omega: f64) -> (f64, f64) {
        let s = Complex::new(0.0, omega);
        let horner = |p: &[f64]| {
            p.iter().fold(Complex::new(0.0, 0.0), |acc, &c| {
                acc * s + Complex::new(c, 0.0)
            })
        };
        let g =
            horner(&self.num) / horner(&self.den) * Complex::from_polar(1.0, -omega * self.delay);
        (g.re, g.im)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn routh_hurwitz_known_polynomials() {
        assert!(routh_hurwitz_stable(&[3.0]));
        assert!(routh_hurwitz_stable(&[1.0, 2.0]));
        assert!(routh_hurwitz_stable(&[-1.0, -2.0])); // normalising den[0] = 1
        assert!(!routh_hurwitz_stable(&[1.0, -2.0]));
        assert!(routh_hurwitz_stable(&[1.0, 0.4, 4.0]));
        assert!(!routh_hurwitz_stable(&[1.0, 0.0, 4.0])); // +-2j: marginal, rejected
        assert!(!routh_hurwitz_stable(&[1.0, 1.0, 0.0])); // root at 0
                                                          // (s+1)(s+2)(s+3) = s^3 + 6 s^2 + 11 s + 6
        assert!(routh_hurwitz_stable(&[1.0, 6.0, 11.0, 6.0]));
        // s^3 + s^2 + s + 1 = (s+1)(s^2+1): marginal
        assert!(!routh_hurwitz_stable(&[1.0, 1.0, 1.0, 1.0]));
        // s^3 + s^2 + 2 s + 8: two roots in the right half-plane
        assert!(!routh_hurwitz_stable(&[1.0, 1.0, 2.0, 8.0]));
        // (s+1)^4 and (s+1)^5
        assert!(routh_hurwitz_stable(&[1.0, 4.0, 6.0, 4.0, 1.0]));
        assert!(routh_hurwitz_stable(&[1.0, 5.0, 10.0, 10.0, 5.0, 1.0]));
        // (s^2 + 0.01 s + 1)(s + 1)^2: lightly damped, still stable
        let p = [1.0, 2.01, 2.02, 2.01, 1.0];
        assert!(routh_hurwitz_stable(&p));
        // (s^2 - 0.01 s + 1)(s + 1)^2
        assert!(!routh_hurwitz_stable(&[1.0, 1.99, 1.98, 1.99, 1.0]));
        assert!(!routh_hurwitz_stable(&[]));
        assert!(!routh_hurwitz_stable(&[0.0, 1.0]));
        assert!(!routh_hurwitz_stable(&[1.0, f64::NAN]));
    }

    #[test]
    fn constructor_validates() {
        let tf = TransferFunction::new(&[0.0, 0.0, 2.0], &[1.0, 3.0], 0.1).unwrap();
        assert_eq!(tf.num(), &[2.0]);
        assert_eq!(tf.order(), 1);
        assert_eq!(tf.delay(), 0.1);
        let zero = TransferFunction::new(&[], &[1.0, 1.0], 0.0).unwrap();
        assert_eq!(zero.num(), &[0.0]);

        let e = TransferFunction::new(&[1.0, 0.0, 0.0], &[1.0, 1.0], 0.0).unwrap_err();
        assert!(matches!(e, CoreError::Improper(_)), "{e}");
        assert!(e
            .to_string()
            .contains("numerator degree 2 > denominator degree 1"));
        let e = TransferFunction::new(&[1.0], &[0.0, 1.0], 0.0).unwrap_err();
        assert!(matches!(e, CoreError::Improper(_)), "{e}");
        let e = TransferFunction::new(&[1.0], &[], 0.0).unwrap_err();
        assert!(matches!(e, CoreError::Improper(_)), "{e}");
        let e = TransferFunction::new(&[1.0], &[1.0, -1.0], 0.0).unwrap_err();
        assert!(matches!(e, CoreError::Unstable(_)), "{e}");
        assert!(e.to_string().contains("Routh-Hurwitz"));
        let e = TransferFunction::new(&[1.0], &[1.0, 1.0], -0.5).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        assert!(e.to_string().contains("delay = -0.5"));
        let e = TransferFunction::new(&[f64::NAN], &[1.0, 1.0], 0.0).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let e = TransferFunction::new(&[1.0], &[1.0, 1.0], f64::INFINITY).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
    }

    /// `C (j omega I - A)^{-1} B + D`, solved densely, against `freq_response` without delay.
    fn realisation_response(c: &Companion, omega: f64) -> Complex<f64> {
        let n = c.order();
        if n == 0 {
            return Complex::new(c.d, 0.0);
        }
        let s = Complex::new(0.0, omega);
        let mut m = nalgebra::DMatrix::<Complex<f64>>::zeros(n, n);
        for j in 0..n {
            m[(0, j)] = Complex::new(c.a[j], 0.0);
        }
        for i in 1..n {
            m[(i, i - 1)] = Complex::new(-1.0, 0.0);
        }
        for i in 0..n {
            m[(i, i)] += s;
        }
        let mut rhs = nalgebra::DVector::<Complex<f64>>::zeros(n);
        rhs[0] = Complex::new(1.0, 0.0);
        let x = m.lu().solve(&rhs).unwrap();
        (0..n).fold(Complex::new(c.d, 0.0), |acc, j| {
            acc + Complex::new(c.c[j], 0.0) * x[j]
        })
    }

    #[test]
    fn realisation_reproduces_freq_response() {
        let cases: [(&[f64], &[f64]); 4] = [
            (&[2.0], &[3.0]),
            (&[1.0, 2.0], &[2.0, 1.0]),
            (&[0.5, 1.0, 2.0], &[1.0, 0.8, 4.0]),
            (&[1.0, -1.0], &[2.0, 12.0, 22.0, 12.0]),
        ];
        for (num, den) in cases {
            let tf = TransferFunction::new(num, den, 0.0).unwrap();
            let comp = tf.realize();
            for &omega in &[0.0, 0.3, 1.0, 2.0, 7.5] {
                let (re, im) = tf.freq_response(omega);
                let g = realisation_response(&comp, omega);
                assert_relative_eq!(re, g.re, epsilon = 1e-12, max_relative = 1e-12);
                assert_relative_eq!(im, g.im, epsilon = 1e-12, max_relative = 1e-12);
            }
        }
    }

    #[test]
    fn freq_response_includes_delay() {
        // G = e^{-0.5 s} / (s + 1) at omega = 2: |G| = 1/sqrt(5), angle = -atan(2) - 1.
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], 0.5).unwrap();
        let (re, im) = tf.freq_response(2.0);
        assert_relative_eq!(re.hypot(im), 1.0 / 5f64.sqrt(), max_relative = 1e-14);
        assert_relative_eq!(im.atan2(re), -(2f64.atan()) - 1.0, max_relative = 1e-14);
    }
}

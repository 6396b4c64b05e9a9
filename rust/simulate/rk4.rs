//! The RK4 scratch of a state of any order, shared by the simulation's integrators
//! (`simulate.rs`'s `integrate`, `on_x.rs`'s `linear_pass`, `with_terms/integrate.rs`): the step
//! sizes, the four stage slopes and the stage point, the step's update and its continuous
//! extension at the middle, each in the one operation order all of them use (so that a state
//! stepped by two of them is the same to the bit).

/// The step `h = dt / substeps` with `h / 2` and `h / 6`, as every integrator computes them.
#[derive(Debug, Clone, Copy)]
pub(super) struct Steps {
    pub(super) h: f64,
    pub(super) half_h: f64,
    pub(super) h_sixth: f64,
}

impl Steps {
    pub(super) fn new(dt: f64, substeps: usize) -> Self {
        let h = dt / substeps as f64;
        Self {
            h,
            half_h: 0.5 * h,
            h_sixth: h / 6.0,
        }
    }
}

/// The stage slopes `k1..k4` and the stage point `tmp` of an order-`n` state, allocated once per
/// run (the fields are borrowed apart: `rhs(&s.tmp, .., &mut s.k2)`).
pub(super) struct Scratch {
    pub(super) k1: Vec<f64>,
    pub(super) k2: Vec<f64>,
    pub(super) k3: Vec<f64>,
    pub(super) k4: Vec<f64>,
    pub(super) tmp: Vec<f64>,
}

impl Scratch {
    pub(super) fn new(n: usize) -> Self {
        Self {
            k1: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            tmp: vec![0.0; n],
        }
    }

    /// The RK4 update `xs += h/6 (k1 + 2 k2 + 2 k3 + k4)`.
    #[inline(always)]
    pub(super) fn advance(&self, xs: &mut [f64], h_sixth: f64) {
        for ((((x, a), b), c), d) in xs
            .iter_mut()
            .zip(&self.k1)
            .zip(&self.k2)
            .zip(&self.k3)
            .zip(&self.k4)
        {
            *x += h_sixth * (a + 2.0 * b + 2.0 * c + d);
        }
    }

    /// The third-order continuous extension of the step at its middle, from the state `xs` at its
    /// start: `xs + h (5 k1 + 4 (k2 + k3) - k4) / 24`, into `out`.
    #[inline(always)]
    pub(super) fn middle(&self, xs: &[f64], h: f64, out: &mut [f64]) {
        for ((((m, x), a), b), (c, d)) in out
            .iter_mut()
            .zip(xs)
            .zip(&self.k1)
            .zip(&self.k2)
            .zip(self.k3.iter().zip(&self.k4))
        {
            *m = x + h * (5.0 * a + 4.0 * (b + c) - d) / 24.0;
        }
    }
}

/// `xs + k * hk`, elementwise into `out` (all of the same length): a stage point.
#[inline(always)]
pub(super) fn axpy(out: &mut [f64], xs: &[f64], hk: f64, k: &[f64]) {
    for ((o, x), ki) in out.iter_mut().zip(xs).zip(k) {
        *o = x + hk * ki;
    }
}

//! Rust core of `bouc_wen_id`: identification of Wiener systems `u -> G(s) -> x -> Bouc-Wen -> w`
//! from sine experiments.
//!
//! Implements the seed paper (Wiener system identification in presence of hysteresis nonlinearity):
//! the Wiener model (1a-c) with the Bouc-Wen hysteresis (2a), periodic averaging (4a-b), the phase
//! estimator (9), the separable least-squares estimator (18)-(24) and the gain estimator (27b).
//! The numerical contract, shared with the NumPy reference `bouc_wen_id.reference`, is
//! `docs/design.md`; every module follows it step by step so that the two agree to rounding.
//!
//! The numerics take `&[f64]` and return [`error::Result`] and know nothing of Python; the pyo3
//! bindings (feature `python`) live in the private folder `rust/bindings/` and only convert, call
//! and convert back.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

pub mod augmented;
pub mod average;
pub mod bouc_wen;
pub mod budget;
pub mod cancel;
pub mod compensate;
pub mod dahl;
pub mod error;
pub mod estimate;
pub mod feedback;
mod hermite;
pub mod lab;
pub mod linear;
mod loop_kernel;
pub mod multistart;
pub mod path_loop;
pub mod profile;
pub mod refine;
pub mod series_loop;
pub mod simulate;
pub mod solve;
pub mod steady;
pub mod terms;
pub mod timedomain;

#[cfg(feature = "python")]
mod bindings;

//! Work and memory budgets checked before a call does its work (issue #9, "Budgets up front").
//!
//! A hostile or careless size (`n_samples = 10^9`, `substeps = 10^12`, a phase grid of `10^8`)
//! must be refused in microseconds with a message that says the size and how to raise the limit,
//! not discovered after minutes of work or when an allocation fails. Each entry estimates its
//! cost from its arguments and calls [`check_samples`], [`check_steps`] or [`check_bytes`].
//!
//! The limits are process-wide and configurable: `bouc_wen_id.budget.set_budget(...)` (or the
//! `BOUC_WEN_ID_MAX_SAMPLES`, `..._MAX_STEPS`, `..._MAX_BYTES` environment variables) writes them
//! here through the binding, and the Python side reads the same values. The defaults let a
//! laboratory-size problem through (tens of millions of samples, about a minute of RK4) and stop
//! anything that would run for hours or fill the memory of a laptop.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{CoreError, Result};

/// Default largest number of samples of one signal a call creates or reads (2^24 = 16.8 M:
/// 134 MB per float64 array).
pub const DEFAULT_MAX_SAMPLES: u64 = 1 << 24;
/// Default largest number of elementary steps of one call: RK4 steps for the integrators, sample
/// evaluations for the searches (about 0.05-0.1 us each, so about a minute).
pub const DEFAULT_MAX_STEPS: u64 = 1_000_000_000;
/// Default largest memory a call may allocate or a file may inflate to (2 GiB).
pub const DEFAULT_MAX_BYTES: u64 = 1 << 31;
/// RK4 steps per sample interval above which nothing is gained (the step error is at rounding
/// long before) and a single interval would run for seconds between two cancellation checks.
pub const MAX_SUBSTEPS: u64 = 1 << 20;

static MAX_SAMPLES: AtomicU64 = AtomicU64::new(DEFAULT_MAX_SAMPLES);
static MAX_STEPS: AtomicU64 = AtomicU64::new(DEFAULT_MAX_STEPS);
static MAX_BYTES: AtomicU64 = AtomicU64::new(DEFAULT_MAX_BYTES);

/// The current limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Samples of one signal.
    pub max_samples: u64,
    /// Elementary steps of one call.
    pub max_steps: u64,
    /// Bytes one call may allocate.
    pub max_bytes: u64,
}

/// The limits in force.
pub fn limits() -> Limits {
    Limits {
        max_samples: MAX_SAMPLES.load(Ordering::Relaxed),
        max_steps: MAX_STEPS.load(Ordering::Relaxed),
        max_bytes: MAX_BYTES.load(Ordering::Relaxed),
    }
}

/// Sets the limits (each `>= 1`); returns the previous ones.
///
/// Errors: [`CoreError::InvalidParameter`] for a zero limit.
pub fn set_limits(new: Limits) -> Result<Limits> {
    for (name, v) in [
        ("max_samples", new.max_samples),
        ("max_steps", new.max_steps),
        ("max_bytes", new.max_bytes),
    ] {
        if v < 1 {
            return Err(CoreError::InvalidParameter(format!(
                "budget {name} = {v} must be >= 1"
            )));
        }
    }
    let old = limits();
    MAX_SAMPLES.store(new.max_samples, Ordering::Relaxed);
    MAX_STEPS.store(new.max_steps, Ordering::Relaxed);
    MAX_BYTES.store(new.max_bytes, Ordering::Relaxed);
    Ok(old)
}

fn refuse(what: &str, size: u128, unit: &str, name: &str, limit: u64) -> CoreError {
    CoreError::BudgetExceeded(format!(
        "{what} needs {size} {unit}, above the budget {name} = {limit}; reduce the request, or \
         raise the limit with bouc_wen_id.budget.set_budget({name}=...) or the environment \
         variable BOUC_WEN_ID_{}",
        name.to_uppercase()
    ))
}

/// Refuses `n` samples of one signal above the `max_samples` budget.
///
/// Errors: [`CoreError::BudgetExceeded`].
pub fn check_samples(what: &str, n: u128) -> Result<()> {
    let limit = MAX_SAMPLES.load(Ordering::Relaxed);
    if n > u128::from(limit) {
        return Err(refuse(what, n, "samples", "max_samples", limit));
    }
    Ok(())
}

/// Refuses `steps` elementary steps above the `max_steps` budget.
///
/// Errors: [`CoreError::BudgetExceeded`].
pub fn check_steps(what: &str, steps: u128) -> Result<()> {
    let limit = MAX_STEPS.load(Ordering::Relaxed);
    if steps > u128::from(limit) {
        return Err(refuse(what, steps, "steps", "max_steps", limit));
    }
    Ok(())
}

/// Refuses `bytes` of memory above the `max_bytes` budget.
///
/// Errors: [`CoreError::BudgetExceeded`].
pub fn check_bytes(what: &str, bytes: u128) -> Result<()> {
    let limit = MAX_BYTES.load(Ordering::Relaxed);
    if bytes > u128::from(limit) {
        return Err(refuse(what, bytes, "bytes", "max_bytes", limit));
    }
    Ok(())
}

/// Refuses `substeps` above [`MAX_SUBSTEPS`] (a fixed ceiling: see there).
///
/// Errors: [`CoreError::BudgetExceeded`].
pub fn check_substeps(substeps: u128) -> Result<()> {
    if substeps > u128::from(MAX_SUBSTEPS) {
        return Err(CoreError::BudgetExceeded(format!(
            "substeps = {substeps} is above {MAX_SUBSTEPS} RK4 steps per sample interval, where \
             the step error is long at rounding; use fewer substeps or a finer sample grid"
        )));
    }
    Ok(())
}

/// The RK4 cost of a simulation of `n_samples` samples with `substeps` steps each: samples of the
/// two outputs, their 16 bytes per sample, and `(n_samples - 1) substeps` steps.
///
/// Errors: [`CoreError::BudgetExceeded`].
pub fn check_simulation(n_samples: usize, substeps: usize) -> Result<()> {
    let n = n_samples as u128;
    check_substeps(substeps as u128)?;
    check_samples("the simulation", n)?;
    check_bytes("the simulation's two outputs", 16 * n)?;
    check_steps(
        "the simulation",
        n.saturating_sub(1).saturating_mul(substeps as u128),
    )
}

/// Typical golden-section reductions of a search (`0.618^50 ~ 4e-11` of the bracket), for the
/// work estimates.
pub const GOLDEN_ITER_ESTIMATE: u128 = 50;
/// Typical shooting passes of a steady or path loop, for the work estimates.
pub const SHOOT_ITER_ESTIMATE: u128 = 4;

/// The long calls of the core and the sizes their work grows with: the one place where a call's
/// step estimate and its budget check are written down. [`Work::check`] refuses a call over the
/// `max_steps` budget and returns the estimate, which also decides whether the call runs
/// interruptibly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Work {
    /// An RK4 simulation of `n_samples` output samples, `substeps` steps each (see
    /// [`check_simulation`]).
    Simulation {
        /// Output samples.
        n_samples: usize,
        /// RK4 steps per sample interval.
        substeps: usize,
    },
    /// The golden-section mu search (24a) on one period of `samples` samples.
    MuSearch {
        /// Samples per period.
        samples: usize,
        /// Reductions allowed; the budget is charged for all of them.
        max_iter: usize,
    },
    /// The steady loop of (2b) on `samples` samples per period.
    SteadyLoop {
        /// Samples per period.
        samples: usize,
        /// RK4 steps per lattice interval.
        substeps: usize,
    },
    /// The loop along the input path (design.md 9.2) on `samples` samples per period.
    PathLoop {
        /// Samples per period.
        samples: usize,
        /// RK4 steps per segment.
        substeps: usize,
    },
    /// The phase profile of the SLS estimator: a mu search at each of `grid` phases.
    PhaseProfile {
        /// Samples per period.
        samples: usize,
        /// Phases of the grid.
        grid: usize,
    },
    /// The phase profile at a further frequency (hysteresis known): one pass per phase.
    PhaseGain {
        /// Samples per period.
        samples: usize,
        /// Phases of the grid.
        grid: usize,
    },
    /// A joint Levenberg-Marquardt of the plain model: every iteration evaluates every loop.
    Refinement {
        /// Samples of all experiments together.
        samples: u128,
        /// Iteration cap.
        max_iter: usize,
        /// RK4 steps per lattice interval.
        substeps: usize,
    },
    /// [`Work::Refinement`] of the augmented model (design.md 9.3).
    AugmentedRefinement {
        /// Samples of all experiments together.
        samples: u128,
        /// Iteration cap.
        max_iter: usize,
        /// RK4 steps per lattice interval / path segment.
        substeps: usize,
    },
    /// `starts` refinements of the multi-start screening. Not charged to the budget (each start
    /// may be abandoned early, and the caller sizes the screening); estimated only, so that it
    /// runs interruptibly.
    Starts {
        /// Starting points.
        starts: usize,
        /// Samples of all experiments together.
        samples: u128,
        /// Iteration cap of each start.
        max_iter: usize,
        /// RK4 steps per lattice interval.
        substeps: usize,
    },
}

/// `iterations x samples x substeps x` [`SHOOT_ITER_ESTIMATE`]: the steps of loop evaluations.
fn shooting(iterations: u128, samples: u128, substeps: usize) -> u128 {
    iterations
        .saturating_mul(samples)
        .saturating_mul(substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE)
}

impl Work {
    /// The estimated elementary steps of the call (RK4 steps, or sample evaluations of the
    /// searches).
    pub fn steps(&self) -> u128 {
        match *self {
            Work::Simulation {
                n_samples,
                substeps,
            } => n_samples.saturating_sub(1).saturating_mul(substeps) as u128,
            Work::MuSearch { samples, .. } => (samples as u128) * GOLDEN_ITER_ESTIMATE,
            Work::SteadyLoop { samples, substeps } | Work::PathLoop { samples, substeps } => {
                shooting(1, samples as u128, substeps)
            }
            Work::PhaseProfile { samples, grid } => (grid as u128)
                .saturating_mul(samples as u128)
                .saturating_mul(GOLDEN_ITER_ESTIMATE),
            Work::PhaseGain { samples, grid } => (grid as u128).saturating_mul(samples as u128),
            Work::Refinement {
                samples,
                max_iter,
                substeps,
            }
            | Work::AugmentedRefinement {
                samples,
                max_iter,
                substeps,
            } => shooting(max_iter as u128, samples, substeps),
            Work::Starts {
                starts,
                samples,
                max_iter,
                substeps,
            } => shooting(
                (starts as u128).saturating_mul(max_iter as u128),
                samples,
                substeps,
            ),
        }
    }

    /// Checks the call against the budgets and returns [`Work::steps`].
    ///
    /// Errors: [`CoreError::BudgetExceeded`], naming the call and the sizes its work grows with.
    pub fn check(&self) -> Result<u128> {
        let steps = self.steps();
        match *self {
            Work::Simulation {
                n_samples,
                substeps,
            } => check_simulation(n_samples, substeps)?,
            Work::MuSearch { samples, max_iter } => check_steps(
                "the mu search",
                (max_iter as u128).saturating_mul(samples as u128),
            )?,
            Work::SteadyLoop { .. } => check_steps("the steady loop", steps)?,
            Work::PathLoop { .. } => check_steps("the path loop (samples x substeps)", steps)?,
            Work::PhaseProfile { .. } => check_steps(
                "the phase profile (grid x samples per period x mu search)",
                steps,
            )?,
            Work::PhaseGain { .. } => {
                check_steps("the phase profile (grid x samples per period)", steps)?
            }
            Work::Refinement { .. } => {
                check_steps("the refinement (max_iter x samples x substeps)", steps)?
            }
            Work::AugmentedRefinement { .. } => check_steps(
                "the augmented refinement (max_iter x samples x substeps)",
                steps,
            )?,
            Work::Starts { .. } => {}
        }
        Ok(steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_refuse_with_the_size_and_the_remedy() {
        // One test touches the process-wide limits, so parallel tests cannot race on them.
        let msg = check_steps("x", 10u128.pow(12)).unwrap_err().to_string();
        assert!(msg.contains("1000000000000 steps"), "{msg}");
        assert!(msg.contains("set_budget(max_steps=...)"), "{msg}");
        assert!(msg.contains("BOUC_WEN_ID_MAX_STEPS"), "{msg}");
        assert!(check_samples("x", u128::from(DEFAULT_MAX_SAMPLES)).is_ok());
        assert!(check_samples("x", u128::from(DEFAULT_MAX_SAMPLES) + 1).is_err());
        assert!(check_simulation(1000, 1 << 21).is_err());
        assert!(check_simulation(1000, 4).is_ok());
        assert!(set_limits(Limits {
            max_samples: 0,
            ..limits()
        })
        .is_err());
        let old = set_limits(Limits {
            max_samples: 10,
            max_steps: 10,
            max_bytes: 10,
        })
        .unwrap();
        assert!(check_simulation(11, 1).is_err());
        assert!(check_bytes("x", 11).is_err());
        set_limits(old).unwrap();
        assert_eq!(limits(), old);
    }
}

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

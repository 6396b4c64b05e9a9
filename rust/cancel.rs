//! Cooperative cancellation of the long loops of the core (issue #9, "Interruptible").
//!
//! The numerics stay free of pyo3: a long loop calls [`checkpoint`] (or, where it cannot return an
//! error, tests [`requested`] and breaks) at a bounded interval, and the binding decides what
//! cancels. The binding (`rust/bindings/detach.rs`, `interruptible`) runs the work on a scoped
//! worker thread with a fresh [`Token`] installed, and the calling thread polls
//! `Python::check_signals` every [`POLL_INTERVAL`] while it waits; on Ctrl-C it cancels the token,
//! waits for the worker to reach its next checkpoint and raises the `KeyboardInterrupt`. This is
//! the usual design of cooperative cancellation (e.g. .NET's `CancellationToken`, Go's
//! `context.Context`): the worker is never killed, so nothing is left half-written and every
//! borrow ends normally.
//!
//! Adopting it in a new loop is one line:
//!
//! ```ignore
//! crate::cancel::checkpoint()?; // once per outer iteration that may take > ~10 ms
//! ```
//!
//! The token is thread-local, so no signature changes; code that fans out to other threads (rayon)
//! carries it with [`current`] / [`with_token`]. With no token installed (plain Rust, `cargo
//! test`) [`checkpoint`] never fails. Cost: one thread-local read and one relaxed atomic load.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crate::error::{CoreError, Result};

/// How often the binding polls for a signal while the worker runs: Ctrl-C is seen within this
/// interval plus the time to the worker's next checkpoint.
pub const POLL_INTERVAL: Duration = Duration::from_millis(50);

/// RK4 steps between two checks in the integrators (about 0.1 ms of work at ~50 ns a step).
pub const CHECK_EVERY_STEPS: usize = 2048;

/// A cancellation flag shared between the thread that decides and the threads that work.
#[derive(Debug, Default)]
pub struct Token(AtomicBool);

impl Token {
    /// A token that is not cancelled.
    pub const fn new() -> Self {
        Self(AtomicBool::new(false))
    }

    /// Asks every loop that checks this token to stop at its next checkpoint.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Token::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Arc<Token>>> = const { RefCell::new(None) };
}

/// `true` when the token installed on this thread was cancelled (for loops that cannot return an
/// error: break, then call [`checkpoint`] where an error can be returned).
#[inline]
pub fn requested() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(|t| t.is_cancelled()))
}

/// `Err(CoreError::Interrupted)` when the token installed on this thread was cancelled.
#[inline]
pub fn checkpoint() -> Result<()> {
    if requested() {
        Err(CoreError::Interrupted(
            "the computation was cancelled (Ctrl-C) before it finished; nothing was returned"
                .into(),
        ))
    } else {
        Ok(())
    }
}

/// The token installed on this thread, to carry into worker threads with [`with_token`].
pub fn current() -> Option<Arc<Token>> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Runs `f` with `token` installed on this thread, then restores the previous one (also when `f`
/// panics).
pub fn with_token<R>(token: Option<Arc<Token>>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Arc<Token>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let prev = self.0.take();
            CURRENT.with(|c| *c.borrow_mut() = prev);
        }
    }
    let prev = CURRENT.with(|c| std::mem::replace(&mut *c.borrow_mut(), token));
    let _restore = Restore(prev);
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoint_fails_only_under_a_cancelled_token() {
        assert!(checkpoint().is_ok());
        let t = Arc::new(Token::new());
        with_token(Some(t.clone()), || {
            assert!(checkpoint().is_ok());
            t.cancel();
            assert!(matches!(checkpoint(), Err(CoreError::Interrupted(_))));
            // A nested scope without a token is not cancelled, and the outer one comes back.
            with_token(None, || assert!(checkpoint().is_ok()));
            assert!(requested());
        });
        assert!(checkpoint().is_ok());
        assert!(current().is_none());
    }

    #[test]
    fn a_cancelled_simulation_stops_early_with_interrupted() {
        use crate::bouc_wen::BoucWen;
        use crate::linear::TransferFunction;
        use crate::simulate::{simulate, Input};
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 0.5, 0.1, 2.0, 0.0).unwrap();
        let t = Arc::new(Token::new());
        t.cancel();
        let input = Input::Sine {
            amplitude: 1.0,
            omega: 1.0,
        };
        let start = std::time::Instant::now();
        let r = with_token(Some(t), || simulate(&tf, &bw, input, 0.01, 1 << 22, 64));
        assert!(matches!(r, Err(CoreError::Interrupted(_))), "{r:?}");
        // 2^28 RK4 steps would take many seconds; the check stops it at once.
        assert!(start.elapsed() < Duration::from_secs(2));
    }
}

//! Releasing the interpreter around the numerics, and interruptible long calls (issue #9).

use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;

use pyo3::prelude::*;

use crate::cancel;
use crate::error::{self, CoreError};

/// Above this many samples, averaging and differentiation release the interpreter: below it the
/// work is shorter than the hand-over.
const DETACH_MIN_SAMPLES: usize = 1 << 14;

/// Below this many elementary steps a call runs inline: a worker thread (about 20 us) would cost
/// more than the few milliseconds the user waits for Ctrl-C.
const INTERRUPTIBLE_MIN_STEPS: u128 = 1 << 16;

/// Runs `work` over `samples` samples, with the interpreter released above
/// [`DETACH_MIN_SAMPLES`].
pub(super) fn by_size<T, F>(py: Python<'_>, samples: usize, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> error::Result<T> + Send,
{
    Ok(if samples >= DETACH_MIN_SAMPLES {
        py.detach(work)
    } else {
        work()
    }?)
}

/// Runs `work` with the interpreter released; when `steps` (an estimate of its elementary steps,
/// [`crate::budget::Work::steps`]) is large, runs it on a scoped worker thread under a fresh
/// [`cancel::Token`] while this thread polls `Python::check_signals` every
/// [`cancel::POLL_INTERVAL`]. On a signal (Ctrl-C) the token is cancelled, the worker stops at its
/// next checkpoint (nothing of its result is kept), and the signal's exception
/// (`KeyboardInterrupt`) is raised.
pub(super) fn interruptible<T, F>(py: Python<'_>, steps: u128, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> error::Result<T> + Send,
{
    if steps < INTERRUPTIBLE_MIN_STEPS {
        return Ok(py.detach(work)?);
    }
    let token = Arc::new(cancel::Token::new());
    let (outcome, signal) = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel::<()>();
            let worker_token = Some(token.clone());
            let spawned = std::thread::Builder::new()
                .name("bouc_wen_id-core".into())
                .spawn_scoped(scope, move || {
                    let out = cancel::with_token(worker_token, work);
                    // The receiver only ends with this scope; a failed send changes nothing.
                    let _ = done.send(());
                    out
                });
            let handle = match spawned {
                Ok(h) => h,
                // No thread to be had (the OS refused one): the work never ran; say so.
                Err(e) => {
                    return (
                        Err(CoreError::InvalidParameter(format!(
                            "could not start a worker thread for an interruptible call: {e}"
                        ))),
                        None,
                    )
                }
            };
            let mut signal: Option<PyErr> = None;
            // Until the worker reports (or drops its end by panicking), poll for signals.
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(cancel::POLL_INTERVAL)
            {
                if signal.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        token.cancel();
                        signal = Some(e);
                    }
                }
            }
            let outcome = match handle.join() {
                Ok(out) => out,
                Err(panic) => std::panic::resume_unwind(panic),
            };
            (outcome, signal)
        })
    });
    if let Some(e) = signal {
        return Err(e);
    }
    Ok(outcome?)
}

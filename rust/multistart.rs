//! Multi-start screening of the joint output-error refinement ([`crate::refine::refine`]), run in
//! parallel across the cores (issue #8; `docs/design.md` §7.4, the generic restarts).
//!
//! The joint fit of the averaged loops can land in a wrong basin; the Python driver then screens a
//! set of generic starts with short fits and finishes only the best. Every start is an independent
//! Levenberg-Marquardt run, so they are spread over a rayon pool; the outcomes come back in the
//! order of the starts and each is exactly what a serial call of `refine` on that start gives, so
//! the result does not depend on the number of threads.
//!
//! Early abandonment (optional): the screening runs in two rounds with a barrier between them.
//! After `first_iter` iterations the best cost over all starts is known; a start whose cost is still
//! above `abandon_ratio` times it is hopeless and stops there (a steady-loop fit that is that far
//! behind after a few LM steps sits in another basin), the others continue from where they stopped
//! for the remaining iterations. The barrier keeps the decision, hence the outcome, independent of
//! the scheduling. Continuing restarts the damping at its initial value, so a continued start is
//! not bitwise the single run of `max_iter` iterations; it is the same for any thread count.

use std::sync::Arc;

use rayon::prelude::*;

use crate::cancel::{self, Token};
use crate::error::{CoreError, Result};
use crate::refine::{refine, Experiment, Fit, Options, Params};

/// Early abandonment of hopeless starts (see the module documentation).
#[derive(Debug, Clone, Copy)]
pub struct Abandon {
    /// LM iterations of the first round (>= 1; at most the iteration cap).
    pub first_iter: usize,
    /// A start whose first-round cost exceeds this multiple of the best first-round cost stops
    /// (> 1).
    pub ratio: f64,
}

/// Outcome of one start.
#[derive(Debug, Clone)]
pub struct StartOutcome {
    /// The fit (iterations summed over the rounds it ran).
    pub fit: Fit,
    /// Whether it was stopped after the first round as hopeless.
    pub abandoned: bool,
}

/// Runs `refine(exps, start, opts)` for every start, `threads` at a time (0: rayon's default, one
/// per core; 1: serially on the calling thread), optionally abandoning hopeless starts early.
///
/// Returns one entry per start, in order: the fit, or the error `refine` raised for that start
/// (e.g. a start that is no valid steady loop). The entries do not depend on `threads`.
///
/// Errors (for the call as a whole): `abandon` with `first_iter == 0` or `ratio <= 1` (or NaN),
/// or a thread pool that cannot be built.
pub fn refine_many(
    exps: &[Experiment],
    starts: &[Params],
    opts: &Options,
    abandon: Option<Abandon>,
    threads: usize,
) -> Result<Vec<Result<StartOutcome>>> {
    if let Some(ab) = abandon {
        if ab.first_iter == 0 || ab.ratio.is_nan() || ab.ratio <= 1.0 {
            return Err(CoreError::InvalidParameter(format!(
                "abandonment needs first_iter >= 1 and ratio > 1, got {} and {}",
                ab.first_iter, ab.ratio
            )));
        }
    }
    // Ctrl-C (rust/cancel.rs): the token installed on the calling thread (the binding's worker) is
    // taken here, before any pool thread runs, and installed around every start (map_ordered).
    let token = cancel::current();
    let run = || screen(exps, starts, opts, abandon, threads, &token);
    match threads {
        0 | 1 => Ok(run()),
        n => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| {
                    CoreError::InvalidParameter(format!("cannot start {n} threads: {e}"))
                })?;
            Ok(pool.install(run))
        }
    }
}

/// `f` over `items`, in order: serially when `threads == 1`, else on the current rayon pool; each
/// call runs under `token` (whatever thread runs it) and, once the token is cancelled, is skipped
/// with `CoreError::Interrupted` (a cancelled batch of starts stops within one start's checkpoint).
fn map_ordered<T: Sync, U: Send>(
    items: &[T],
    threads: usize,
    token: &Option<Arc<Token>>,
    f: impl Fn(&T) -> Result<U> + Sync + Send,
) -> Vec<Result<U>> {
    let g = |x: &T| cancel::with_token(token.clone(), || cancel::checkpoint().and_then(|()| f(x)));
    if threads == 1 {
        items.iter().map(g).collect()
    } else {
        items.par_iter().map(g).collect()
    }
}

fn screen(
    exps: &[Experiment],
    starts: &[Params],
    opts: &Options,
    abandon: Option<Abandon>,
    threads: usize,
    token: &Option<Arc<Token>>,
) -> Vec<Result<StartOutcome>> {
    let Some(ab) = abandon.filter(|ab| ab.first_iter < opts.max_iter) else {
        return map_ordered(starts, threads, token, |s| {
            refine(exps, s, opts).map(|fit| StartOutcome {
                fit,
                abandoned: false,
            })
        });
    };
    let first_opts = Options {
        max_iter: ab.first_iter,
        ..*opts
    };
    let first: Vec<Result<Fit>> =
        map_ordered(starts, threads, token, |s| refine(exps, s, &first_opts));
    let best = first
        .iter()
        .filter_map(|r| r.as_ref().ok().map(|f| f.cost))
        .fold(f64::INFINITY, f64::min);
    let rest_opts = Options {
        max_iter: opts.max_iter - ab.first_iter,
        ..*opts
    };
    let items: Vec<Result<Fit>> = first;
    map_ordered(&items, threads, token, |r| {
        let fit = r.as_ref().map_err(Clone::clone)?;
        if fit.converged || fit.cost > ab.ratio * best {
            return Ok(StartOutcome {
                fit: fit.clone(),
                abandoned: !fit.converged,
            });
        }
        let mut more = refine(exps, &fit.params, &rest_opts)?;
        more.iterations += fit.iterations;
        Ok(StartOutcome {
            fit: more,
            abandoned: false,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::steady::steady_loop;

    fn problem() -> (Vec<Vec<f64>>, Vec<f64>) {
        let (beta, gamma, mu) = (0.8, 0.2, 1.6);
        let amps = vec![2.0, 1.0, 0.6];
        let ys = amps
            .iter()
            .enumerate()
            .map(|(i, a)| {
                steady_loop(a * 1.1, beta, gamma, mu, 0.4 + 0.3 * i as f64, 96, 4)
                    .unwrap()
                    .w
            })
            .collect();
        (ys, amps)
    }

    fn starts() -> Vec<Params> {
        [
            (0.5, 0.1, 1.3),
            (2.0, -1.0, 3.0),
            (0.9, 0.9, 2.0),
            (0.3, 0.0, 5.0),
        ]
        .iter()
        .map(|&(beta, gamma, mu)| Params {
            beta,
            gamma,
            mu,
            gains: vec![1.0; 3],
            phases: vec![0.3, 0.6, 0.9],
        })
        .collect()
    }

    fn exps<'a>(ys: &'a [Vec<f64>], amps: &[f64]) -> Vec<Experiment<'a>> {
        crate::refine::unit_experiments(ys, amps)
    }

    #[test]
    fn parallel_equals_serial_and_single_runs() {
        let (ys, amps) = problem();
        let exps = exps(&ys, &amps);
        let opts = Options {
            max_iter: 15,
            ..Options::default()
        };
        let starts = starts();
        let serial = refine_many(&exps, &starts, &opts, None, 1).unwrap();
        let parallel = refine_many(&exps, &starts, &opts, None, 3).unwrap();
        assert_eq!(serial.len(), starts.len());
        for ((s, p), start) in serial.iter().zip(&parallel).zip(&starts) {
            let single = refine(&exps, start, &opts);
            match (s, p, single) {
                (Ok(s), Ok(p), Ok(one)) => {
                    assert_eq!(s.fit.params, p.fit.params);
                    assert_eq!(s.fit.params, one.params);
                    assert_eq!(s.fit.cost.to_bits(), one.cost.to_bits());
                    assert_eq!(s.fit.iterations, p.fit.iterations);
                    assert!(!s.abandoned && !p.abandoned);
                }
                (Err(a), Err(b), Err(c)) => {
                    assert_eq!(a.to_string(), b.to_string());
                    assert_eq!(a.to_string(), c.to_string());
                }
                other => panic!("outcomes differ: {other:?}"),
            }
        }
    }

    #[test]
    fn abandonment_is_deterministic_and_keeps_the_best() {
        let (ys, amps) = problem();
        let exps = exps(&ys, &amps);
        let opts = Options {
            max_iter: 30,
            ..Options::default()
        };
        let ab = Some(Abandon {
            first_iter: 3,
            ratio: 2.0,
        });
        let starts = starts();
        let serial = refine_many(&exps, &starts, &opts, ab, 1).unwrap();
        let parallel = refine_many(&exps, &starts, &opts, ab, 2).unwrap();
        let round1 = Options {
            max_iter: 3,
            ..opts
        };
        let first: Vec<(f64, bool)> = starts
            .iter()
            .map(|s| {
                refine(&exps, s, &round1).map_or((f64::INFINITY, true), |f| (f.cost, f.converged))
            })
            .collect();
        let best = first.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
        let mut abandoned = 0;
        for (i, (s, p)) in serial.iter().zip(&parallel).enumerate() {
            let (s, p) = (s.as_ref().unwrap(), p.as_ref().unwrap());
            assert_eq!(s.fit.params, p.fit.params);
            assert_eq!(s.abandoned, p.abandoned);
            // Abandoned exactly when its first-round cost is over twice the best one (unconverged).
            let (cost, converged) = first[i];
            assert_eq!(s.abandoned, cost > 2.0 * best && !converged);
            if s.abandoned {
                abandoned += 1;
                assert_eq!(s.fit.iterations, 3);
                assert_eq!(s.fit.cost.to_bits(), cost.to_bits());
            }
            if cost == best {
                assert!(!s.abandoned);
                assert!(s.fit.cost <= cost);
            }
        }
        // The best start ends near the exact parameters (noise-free data).
        let winner = serial
            .iter()
            .filter_map(|r| r.as_ref().ok())
            .min_by(|a, b| a.fit.cost.total_cmp(&b.fit.cost))
            .unwrap();
        assert!(
            (winner.fit.params.mu - 1.6).abs() < 1e-3,
            "{:?}",
            winner.fit.params
        );
        assert!(
            abandoned >= 1,
            "no start was abandoned: the test does not exercise it"
        );

        let bad = Abandon {
            first_iter: 0,
            ratio: 2.0,
        };
        assert!(refine_many(&exps, &starts, &opts, Some(bad), 1).is_err());
        let bad = Abandon {
            first_iter: 2,
            ratio: 1.0,
        };
        assert!(refine_many(&exps, &starts, &opts, Some(bad), 1).is_err());
    }

    #[test]
    fn a_cancelled_token_reaches_every_start_on_every_thread_count() {
        let (ys, amps) = problem();
        let exps = exps(&ys, &amps);
        let opts = Options::default();
        let ab = Some(Abandon {
            first_iter: 3,
            ratio: 2.0,
        });
        let token = Arc::new(Token::new());
        token.cancel();
        // 0: the global pool, 1: this thread, 2: a pool of its own; with and without the two rounds.
        for threads in [0, 1, 2] {
            for abandon in [None, ab] {
                let out = cancel::with_token(Some(token.clone()), || {
                    refine_many(&exps, &starts(), &opts, abandon, threads).unwrap()
                });
                for r in &out {
                    assert!(matches!(r, Err(CoreError::Interrupted(_))), "{r:?}");
                }
            }
        }
        // Without a token nothing is cancelled.
        let out = refine_many(&exps, &starts(), &opts, None, 2).unwrap();
        assert!(out.iter().any(|r| r.is_ok()));
    }
}

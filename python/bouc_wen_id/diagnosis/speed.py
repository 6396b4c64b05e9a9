"""The diagnosis's speed switches (issue 18 item 4; docs/diagnosis-speed.md).

Each switch changes how fast ``diagnose`` runs, never what it finds (the verdicts, named terms and values
are those of the code without it: benches/diagnosis_speed.py runs both in one process and checks them).
They exist so that the speed bench can measure "before" and "after" at the same moment on the same
machine; a user has no reason to turn them off.
"""

from __future__ import annotations

#: Run the diagnosis with one BLAS thread (:func:`bouc_wen_id._threads.one_blas_thread`; the caller's
#: setting is restored after). With NumPy's default (one thread per core), the law test's SVD of a
#: 1800 x 40 matrix took 0.2-0.85 s instead of 8 ms on the 2-core machine under load: the BLAS threads
#: compete with the core's rayon threads for the same cores, and spin-wait after each call.
ONE_BLAS_THREAD = True

#: Screen the phases of a linear phase-screened term (dry friction on x) at every level from one loop per
#: phase offset (:func:`bouc_wen_id.diagnosis.fitting.screen_phases_linear`) instead of one per level.
SCREEN_ONCE = True

#: Cache the drift correction's simulated mean periods on their inputs (:func:`bouc_wen_id.diagnosis.drift.
#: _mean_period`): the degradation refinement re-simulated the d = 0 loop, the same at every d it tries.
CACHE_DRIFT_LOOPS = True

#: Fit each (model, candidate term) once per forward selection (:func:`bouc_wen_id.diagnosis.select.
#: memo_fit_with`): an alternative's two-term fit is the next step's trial of that term.
MEMO_FITS = True

#: Simulate a fractional unrecorded age's two whole lead counts as one record (:func:`bouc_wen_id.diagnosis.
#: drift._plans`): the shorter lead's record is the prefix of the longer one's (same drive, same time grid).
SHARE_AGE_LEADS = True

#: Run the drift correction's simulations (one per experiment, lead and d) on up to one thread per core
#: (:func:`bouc_wen_id.diagnosis.drift._run_all`): each is independent, in the Rust core without the
#: interpreter's lock. The unrecorded-age estimate of MR 0.75 A spent 13 of its 30 s in them.
THREAD_DRIFT_SIMS = True

#: Share a candidate's fit between diagnoses of the same data (:mod:`bouc_wen_id.diagnosis.fit_share`): the
#: joint selection of ``diagnose_across`` refitted, at each condition, the candidates that condition's own
#: diagnosis had fitted from the same model on the same periods.
SHARE_FITS = True

#: Diagnose only the settled experiments when some loops still drift and no degradation explains it,
#: deciding after the degradation stage (:class:`bouc_wen_id.diagnosis.run._LeaveOut`), instead of
#: diagnosing the whole set first and throwing that diagnosis away (the wire rope's 13 s, half of it).
LEAVE_OUT_EARLY = True

#: Fit a selection step's candidates on up to one thread per core (:func:`bouc_wen_id.diagnosis.prefetch.
#: in_order`): each is independent, in the Rust core without the interpreter's lock. One MR current level's
#: candidate fits used 1.1 of the machine's 2 cores (review 40).
THREAD_CANDIDATE_FITS = True

#: Fit a model from a start once per diagnosis (:func:`bouc_wen_id.diagnosis.fit_share.refit`): the same
#: start on the same periods was refined again by the detection limits, the second carry and the plain fit
#: (session 43: about 55 of MR 0.5 A's 607 refinements).
MEMO_REFITS = True

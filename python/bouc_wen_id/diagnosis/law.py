"""The law test: a term's claim that one value holds for every experiment (and, for a two-parameter
element or pinching, its branch shape or band too), tested per experiment on the fitted model.

Split from select.py (the forward selection), which re-exports every name here; the test itself is
described in :func:`law_test`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Optional

import numpy as np

from ..augmented import AugExperiment, AugFit, augmented_output
from ..errors import BudgetExceededError
from ..terms import TERMS, Distortion, Offset
from . import free_dc
from .dc_between import slow_dc_now
from .pinch_shape import band_test, is_pinching
from .shape import shape_test, spectral_meat

#: Relative threshold of the law test: a column of the term below it (of its largest) is taken as zero (the
#: term does not act there), and the contrasts' covariance is inverted, and its degrees of freedom counted,
#: over the eigenvalues above it (of the largest).
LAW_RCOND = 1e-10


def law_test(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> float:
    """p-value of the term's law: one value shared by every experiment (the library's claim for a term).

    A Wald test, valid under misfit, of the term's parameter freed per experiment: at ``fit``, one
    Gauss-Newton step of the model whose shared column of the term is split by experiment (``D``), beside
    the shared Bouc-Wen parameters, every other term and each experiment's own (|G|, phi) (``J``); the
    m - 1 contrasts of the m per-experiment values against chi-square(m - 1). Their covariance is a
    sandwich, ``B M B`` with ``B = ([J D]^T [J D])^+``: the meat ``M`` takes each experiment's residual
    (after the step) as a stationary periodic process with its own spectrum (the smoothed periodogram,
    :func:`shape.spectral_meat`), not white noise. A misfit sits in a few low harmonics, the same ones the
    term's column fills, so its leak into each experiment's value is that harmonic power projected on the
    column, not the residual variance per sample: with thousands of samples the per-sample F test called
    every leak "significant" (the MR damper at chi2/dof 84-556: p = 1e-58). Where the model fits (white
    residual at the noise floor) the meat is the classical one and the test the classical score/Wald
    test. Only the experiments the term acts on (a non-zero column) are compared. NaN with fewer than two
    of them or a column the Jacobian cannot give.
    """
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    if term == Offset.kind and slow_dc_now():  # a DC's law under a noise coloured at the DC (dc_between)
        return math.nan
    step = freed_step(exps, fit, term, substeps)
    if step is None:
        return math.nan
    beta, cov, scale, cols = step
    got = contrast_statistic(beta, cov, scale, [c[law_rows(exps, term)] for c in cols])
    if got is None:
        return math.nan
    stat, df = got
    return float(chdtrc(df, max(stat, 0.0)))


def freed_step(
    exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int
) -> Optional[tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]]:
    """:func:`law_test`'s step: ``(beta, cov, scale, cols)``, the Gauss-Newton step in scaled coordinates
    with its sandwich covariance, the column scales, and per claimed value (the term's, its companion's)
    the columns of that value freed per experiment (experiment ``i`` at ``cols[q][i]``; its value is
    ``fit``'s plus ``beta[c] / scale[c]``). None where :func:`law_test` is NaN before its contrasts."""
    par = fit.params
    m = len(exps)
    if m < 2 or term not in par.terms:
        return None
    # A two-parameter element (Dahl friction: its level and its pre-sliding stiffness) claims both values
    # for all experiments: both columns are freed per experiment, 2 (m - 1) contrasts.
    comp = TERMS[term].companion if term in TERMS else ""
    ks = [3 + par.terms.index(t) for t in (term, comp) if t and t in par.terms]
    nk = len(ks)
    nsh = 3 + len(par.terms) - nk
    xs, res, slow = [], [], slow_dc_now()
    try:
        for i, e in enumerate(exps):
            out = augmented_output(e, par, i, substeps=substeps, jacobian=True)
            x = np.zeros((e.ybar.size, nsh + (2 + nk) * m))
            x[:, :nsh] = np.delete(out.jacobian, ks, axis=1)
            x[:, nsh + 2 * i : nsh + 2 * i + 2] = out.own_jacobian
            for j, k in enumerate(ks):
                x[:, nsh + 2 * m + j * m + i] = out.jacobian[:, k]
            sw = math.sqrt(e.weight)
            xs.append(sw * _centred(e, x, slow))  # a free DC (free_dc.py): no weight on the mean
            res.append(sw * _centred(e, e.ybar - out.y, slow))
    except BudgetExceededError:
        raise  # the user's budget is theirs: never turned into "the law is not tested"
    except Exception:  # noqa: BLE001 - a model the core cannot differentiate: the law is not tested
        return None
    xa, r = np.vstack(xs), np.concatenate(res)
    if not (np.all(np.isfinite(xa)) and np.all(np.isfinite(r))):
        return None
    scale = np.linalg.norm(xa, axis=0) + 1e-300
    xa = xa / scale
    sv = np.linalg.svd(xa, compute_uv=False)
    rank = int(np.sum(sv > 1e-10 * sv[0])) + (m if slow else free_dc.count(exps))  # + the centred DCs' dof
    beta = np.linalg.lstsq(xa, r, rcond=1e-10)[0]
    if r.size - rank < 1:
        return None
    bread = np.linalg.pinv(xa.T @ xa, rcond=1e-12)
    meat = np.zeros_like(bread)
    start = 0
    for x in xs:
        n_i = x.shape[0]
        sl = slice(start, start + n_i)
        meat += spectral_meat(xa[sl], r[sl] - xa[sl] @ beta, r.size / (r.size - rank))
        start += n_i
    cov = bread @ meat @ bread
    return beta, cov, scale, [nsh + 2 * m + q * m + np.arange(m) for q in range(nk)]


def _centred(e: AugExperiment, a: np.ndarray, slow: bool) -> np.ndarray:
    """``a`` less its mean under a noise coloured at the DC (``slow``: dc_between.py), else
    free_dc.centred's."""
    return np.asarray(a - np.mean(a, axis=0), dtype=np.float64) if slow else free_dc.centred(e, a)


#: Clean-input experiments the law test needs before it compares them alone (:func:`law_rows`).
MIN_CLEAN = 3


def law_rows(exps: Sequence[AugExperiment], term: str) -> np.ndarray:
    """The experiments whose values the law compares: those with a pure-sine input when at least
    :data:`MIN_CLEAN` have one and some input is not a sine (its ``waveform``: an actuator that clips).
    The model's latent ``x`` is a sine there, the true one carries the input's harmonics through G, and
    the term's value fitted on such an experiment takes them up (blind ``viscous@x:30:0:clipped``: its
    law failed at p = 0.009 with the clipped experiments in, the term was named from the six clean ones
    alone). Every experiment otherwise, and for the input's own term (``distortion``, which acts only
    where the input is not a sine). Two clean experiments were too few (review 32: with 7 of blind's 9
    inputs clipping, the two clean ones passed a false series dashpot for Prandtl-Ishlinskii and a play
    for output backlash, whose laws over all nine failed at p = 2e-14 and 2e-22)."""
    clean = [i for i, e in enumerate(exps) if not e.waveform.size]
    if term == Distortion.kind or len(clean) < MIN_CLEAN or len(clean) == len(exps):
        return np.arange(len(exps))
    return np.array(clean)


def contrast_statistic(
    beta: np.ndarray, cov: np.ndarray, scale: np.ndarray, groups: Sequence[np.ndarray]
) -> Optional[tuple[float, int]]:
    """The law test's Wald statistic and its degrees of freedom: ``beta`` and ``cov`` in scaled coordinates
    (column ``c``'s value is ``beta[c] / scale[c]``), each group the columns of one claimed value freed per
    experiment; None when no group has two experiments the term acts on, or nothing is left to test.

    Contrasts of the per-experiment values, each against the experiment of the largest column, among those
    whose column is not zero (below :data:`LAW_RCOND` of the largest): an experiment the term does not act
    on (the input-waveform term on a clean sine) has no value of its own to compare. Each row is normalised,
    so a small column (1e-6..1e-9 of the largest: a nearly clean input) does not scale every row by its
    1/scale and push the informative contrasts below the pseudo-inverse's cut (review of session 30: with
    each against the last, the statistic collapsed to ~0, p = 1, a real law failure hidden); the inverse
    and the degrees of freedom are taken over the same eigenvalues (above :data:`LAW_RCOND` of the
    largest)."""
    rows = []
    for cols in groups:
        seen = cols[scale[cols] > LAW_RCOND * scale[cols].max()]
        if seen.size < 2:
            continue
        ref = seen[int(np.argmax(scale[seen]))]
        for c in seen[seen != ref]:
            # (1/s_c, -1/s_ref) normalised, written as (s_ref, -s_c) / hypot: no overflow at a tiny s_c
            row = np.zeros(beta.size)
            row[c], row[ref] = scale[ref], -scale[c]
            rows.append(row / math.hypot(float(scale[ref]), float(scale[c])))
    if not rows:
        return None
    contrast = np.array(rows)
    d = contrast @ beta
    w, vec = np.linalg.eigh(contrast @ cov @ contrast.T)
    keep = w > LAW_RCOND * float(w.max())
    stat = float(np.sum((vec[:, keep].T @ d) ** 2 / w[keep]))
    df = int(np.count_nonzero(keep))
    return (stat, df) if df > 0 and math.isfinite(stat) else None


def element_law_test(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> float:
    """p-value of everything a term claims: :func:`law_test` (one value for all experiments) and, for a
    two-parameter element (Dahl friction), its branch shape too (:func:`shape.shape_test`, exponent 1),
    Bonferroni over the two. The bench's Iwan loop (a sum of stops on x) was named Dahl friction "in part"
    in 9 of 20 cases at 30x with its values shared: its branch is not Dahl's."""
    p = law_test(exps, fit, term, substeps)
    if is_pinching(term):  # pinching claims its band too (pinch_shape.band_test: centre and width)
        ps = [v for v in (p, band_test(exps, fit, term, substeps)) if math.isfinite(v)]
        return min(1.0, len(ps) * min(ps)) if ps else math.nan
    if not (term in TERMS and TERMS[term].companion):
        return p
    ps = [v for v in (p, shape_test(exps, fit, term, substeps)) if math.isfinite(v)]
    return min(1.0, len(ps) * min(ps)) if ps else math.nan


__all__ = [
    "LAW_RCOND",
    "MIN_CLEAN",
    "contrast_statistic",
    "element_law_test",
    "freed_step",
    "law_rows",
    "law_test",
]

"""Candidate fits shared between diagnoses of the same data (:data:`speed.SHARE_FITS`).

``diagnose_across`` given each condition's own diagnosis (``per_condition``) refitted, at every condition,
the candidates that condition's own forward selection had already fitted from the same model on the same
averaged periods: the MR damper's joint selection over its five current levels spent most of its time there.
A candidate's fit (``fit_with`` and its wide starts, :func:`select.memo_fit_with`) is a function of its
inputs only, so each diagnosis keeps its fits (``Diagnosis.fits``, not serialised, dropped when pickled)
under a digest of everything the fit reads: the experiments, the model it starts from, the term, the
substeps, the speed switches and the budget. ``diagnose_across`` looks its fits up in its conditions' own
diagnoses' stores: the same inputs give the stored fit (the same object, the same numbers bit for bit); any
difference in them is another key, a new fit. Outside a :func:`scope` nothing is kept.
"""

from __future__ import annotations

import hashlib
import math
import pickle
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Optional

from . import speed


class Store(dict[bytes, Optional[Any]]):
    """One diagnosis's fits by the digest of their inputs, with its hits and misses; pickled empty (the fits
    are a cache, not a result)."""

    hits = 0
    misses = 0

    def __reduce__(self) -> tuple[Any, ...]:
        return (Store, ())


_active: ContextVar[Optional[Store]] = ContextVar("bouc_wen_id_fit_share", default=None)


@contextmanager
def scope(seeds: Iterable[Optional[Store]] = ()) -> Iterator[Store]:
    """The store the fits inside the block go to and are looked up in: the enclosing block's when there is
    one (a diagnosis run inside ``diagnose_across``), else a new one holding the fits of ``seeds`` (other
    diagnoses' stores; None entries skipped)."""
    outer = _active.get()
    store = outer if outer is not None else Store()
    for seed in seeds:
        if seed is not None and seed is not store:
            store.update(seed)
    token = _active.set(store)
    try:
        yield store
    finally:
        _active.reset(token)


def _key(exps: Sequence[Any], base: Any, term: str, substeps: int, tag: Sequence[Any]) -> Optional[bytes]:
    """The digest of a fit's inputs (``tag``: the fitting functions in use, by name and identity, so a
    replaced one is another key), or None when they cannot be pickled (then nothing is shared)."""
    terms = (*getattr(getattr(base, "params", None), "terms", ()), term)
    return _digest((_plain_unless_distortion(exps, terms), base, term, int(substeps)), tag)


def _plain_unless_distortion(exps: Sequence[Any], terms: Sequence[str]) -> list[Any]:
    """``exps``, their waveforms emptied when ``terms`` (the fitted model's) lack the distortion term."""
    from dataclasses import replace

    import numpy as np

    from ..terms import Distortion

    if Distortion.kind in terms:
        return list(exps)
    # The input's waveform enters a fit only through the distortion term (rust/augmented/hysteresis.rs:
    # its column scales the waveform; fitting.py reads it only to carry it through G): without the term
    # two experiments that differ only there give the same fit. diagnose carries the waveforms through
    # G (carry_through_g) and diagnose_across, without the distortion candidate, does not; the second
    # carry (carry_refresh.py) refits the plain model on periods whose waveforms alone differ.
    plain = np.zeros(0)
    return [replace(e, waveform=plain) if getattr(e, "waveform", None) is not None else e for e in exps]


def _digest(inputs: tuple[Any, ...], tag: Sequence[Any]) -> Optional[bytes]:
    """The digest of ``inputs`` with the speed switches, the budget and the fitting functions ``tag`` (by
    name and identity), or None when they cannot be pickled."""
    from .. import budget

    switches = tuple(sorted((k, v) for k, v in vars(speed).items() if k.isupper()))
    names = tuple((getattr(f, "__module__", ""), getattr(f, "__qualname__", ""), id(f)) for f in tag)
    try:
        raw = pickle.dumps((*inputs, switches, budget.get_budget(), names), protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # noqa: BLE001 - an input that does not pickle is fitted, not shared
        return None
    return hashlib.blake2b(raw, digest_size=32).digest()


def shared(
    exps: Sequence[Any],
    base: Any,
    term: str,
    substeps: int,
    fit: Callable[[], Optional[Any]],
    tag: Sequence[Any] = (),
) -> Optional[Any]:
    """``fit()`` (the candidate ``term`` fitted on ``exps`` from ``base``), or the stored result of the same
    inputs inside a :func:`scope` when :data:`speed.SHARE_FITS`."""
    store = _active.get()
    if store is None or not speed.SHARE_FITS:
        return fit()
    return _stored(store, _key(exps, base, term, substeps, tag), fit)


def _stored(store: Store, key: Optional[bytes], fit: Callable[[], Optional[Any]]) -> Optional[Any]:
    """``store[key]``, else ``fit()`` stored there (and not stored when ``key`` is None)."""
    if key is None:
        return fit()
    if key in store:
        store.hits += 1
        return store[key]
    store.misses += 1
    out = fit()
    store[key] = out
    return out


def refit(
    exps: Sequence[Any],
    start: Any,
    substeps: int,
    max_iter: int,
    fit: Callable[[], Optional[Any]],
    tag: Sequence[Any] = (),
    rule: float = math.nan,
) -> Optional[Any]:
    """``fit()`` (one fit of ``start`` on ``exps``, :func:`.fitting.fit_from`, its per-step stop at ``rule``),
    or the stored result of the same inputs inside a :func:`scope` when :data:`speed.MEMO_REFITS`. The inputs
    the fit reads are the key (the waveforms only when ``start`` holds the distortion term), so only a fit
    run again from the very same start on the same periods under the same stop is taken from the store
    (session 43: about 55 of the 607 refinements of MR 0.5 A, the detection limits', the second carry's and
    the plain fit's, repeated earlier ones).
    ``tag``: the fitting functions in use, as in :func:`shared`."""
    store = _active.get()
    if store is None or not speed.MEMO_REFITS:
        return fit()
    return _stored(
        store,
        _digest(
            (
                "fit_from",
                _plain_unless_distortion(exps, start.terms),
                start,
                int(substeps),
                int(max_iter),
                float(rule),
            ),
            tag,
        ),
        fit,
    )

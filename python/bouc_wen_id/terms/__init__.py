"""Physical terms of the augmented model (docs/design.md section 9.1), as first-class parts of a plant.

Each term is a frozen value with exactly one fitted parameter (plus, for Coulomb friction, a fixed
smoothing), in the spirit of lmfit's model components: it knows its code name, its parameter's symbol
and units, what it means physically and what its absence leaves in the residual of a plain fit.  A
:class:`~bouc_wen_id.model.WienerPlant` carries a tuple of them::

    y = y0 + Lag_tau[ w + k u + c udot + m uddot + f tanh(udot / (eps Vmax)) ]
    wdot = alpha xpdot - beta |xpdot| |w|^(mu-1) w - gamma xpdot |w|^mu - delta xpdot |w|^(mu-1) w
    xp = Play_b[x]

Each term class is the one place its vocabulary lives: code name (:attr:`Term.kind`, also the Rust core's
``TermKind``), symbol, units, label, description, residual signature, admissible and physical range, the
diagnosis's start guess (:meth:`Term.start`), how it scales with the data's units, and where it acts
(:class:`Place`). :data:`TERMS` registers them; the CLI's choices, the diagnosis's candidates and labels, the
augmented model's names and the JSON all derive from it. A new term is one class in the module of its place
and one line in :data:`TERMS` (plus its Rust match arm, its oracle and its tests).

This package is the one import for users and the library (``from bouc_wen_id import terms as T``); its modules
hold one job each: ``_base`` the protocol (:class:`Place`, :class:`StartContext`, :class:`Term`), then the
terms by where they act, ``_on_output`` (offset, sensor lag), ``_mechanical`` (stiffness, viscous, inertia,
Coulomb and Dahl friction, on u and on x) and ``_hysteretic`` (asymmetry, play, degradations, pinching,
distortion, series dashpot); this file is the registry itself. Every class is published here as
``bouc_wen_id.terms.<Name>`` (its ``__module__``), so pickles name the same path as before the split.

The units are templates in ``{y}`` (the output's unit) and ``{u}`` (the input's); fill them with
:meth:`Term.units`.  ``x`` has the units of ``y`` in the identified (alpha = 1) model, so play is in
``{y}`` there.
"""

from __future__ import annotations

# Callable, ClassVar: the classes published here (__module__ this package) have string annotations naming
# them, which typing.get_type_hints resolves in this namespace (noqa F401: used only that way).
from collections.abc import Callable as Callable  # noqa: F401
from collections.abc import Iterable, Mapping, Sequence
from typing import Any
from typing import ClassVar as ClassVar  # noqa: F401

from .._term_at import PlaceAt as PlaceAt  # noqa: F401 (Term.at's annotation resolves here)
from ..errors import InvalidParameterError
from ._base import NON_NEGATIVE as NON_NEGATIVE  # the ranges and the smoothing's limit, attributes before the
from ._base import UNBOUNDED as UNBOUNDED  # split, stay reachable here (not in __all__)
from ._base import Place, StartContext, Term, placed_kind
from ._hysteretic import (
    PINCHING_CENTRE,
    PINCHING_WIDTH,
    Asymmetry,
    Degradation,
    Distortion,
    Pinching,
    Play,
    SeriesDashpot,
    StiffnessDegradation,
)
from ._mechanical import (
    COULOMB_SMOOTHING,
    MECHANICAL_PLACES,
    Coulomb,
    CoulombX,
    Dahl,
    DahlSigma,
    DahlSigmaX,
    DahlX,
    Inertia,
    InertiaX,
    Stiffness,
    StiffnessX,
    Viscous,
    ViscousX,
)
from ._mechanical import (
    COULOMB_SMOOTHING_MAX as COULOMB_SMOOTHING_MAX,
)
from ._on_output import Offset, SensorLag

__all__ = [
    "Place",
    "StartContext",
    "Term",
    "Offset",
    "Stiffness",
    "Viscous",
    "Inertia",
    "Coulomb",
    "SensorLag",
    "Asymmetry",
    "Play",
    "Degradation",
    "StiffnessDegradation",
    "Pinching",
    "PINCHING_CENTRE",
    "PINCHING_WIDTH",
    "Distortion",
    "SeriesDashpot",
    "Dahl",
    "DahlSigma",
    "DahlX",
    "DahlSigmaX",
    "StiffnessX",
    "ViscousX",
    "InertiaX",
    "CoulombX",
    "MECHANICAL_PLACES",
    "placed_kind",
    "TERMS",
    "TERM_NAMES",
    "STEADY_TERM_NAMES",
    "DIAGNOSIS_CANDIDATES",
    "parse_terms",
    "physical_value",
    "COULOMB_SMOOTHING",
    "term_from_dict",
    "core_terms",
]


#: Code name -> term class, in the order of the design.md 9.1 table (then the terms at their second place).
TERMS: dict[str, type[Term]] = {
    cls.kind: cls
    for cls in (
        Offset,
        Stiffness,
        Viscous,
        Inertia,
        Coulomb,
        SensorLag,
        Asymmetry,
        Play,
        Degradation,
        StiffnessDegradation,
        Pinching,
        Distortion,
        StiffnessX,
        ViscousX,
        InertiaX,
        CoulombX,
        SeriesDashpot,
        Dahl,
        DahlSigma,
        DahlX,
        DahlSigmaX,
    )
}

#: Every code name, in the order of the design.md 9.1 table.
TERM_NAMES: tuple[str, ...] = tuple(TERMS)
#: The terms seen on the averaged steady period: the augmented model's (design.md 9.3).
STEADY_TERM_NAMES: tuple[str, ...] = tuple(k for k, cls in TERMS.items() if cls.steady)
#: The diagnosis's candidates: the steady terms, then those fitted from the period record (design.md 10.6). A
#: two-parameter element's second term (:attr:`Term.part_of`) is added with its first, not on its own.
DIAGNOSIS_CANDIDATES: tuple[str, ...] = tuple(k for k in STEADY_TERM_NAMES if not TERMS[k].part_of) + tuple(
    k for k, cls in TERMS.items() if k not in STEADY_TERM_NAMES and cls.diagnosable
)


def physical_value(name: str, value: float) -> bool:
    """Whether ``value`` lies in the physical range of the term called ``name`` (:attr:`Term.physical`)."""
    if name not in TERMS:
        raise InvalidParameterError(f"unknown term {name!r}; the terms are {', '.join(TERMS)}")
    lo, hi = TERMS[name].physical
    return lo <= value <= hi


def parse_terms(names: Sequence[str], allowed: Sequence[str] = TERM_NAMES) -> tuple[str, ...]:
    """The code names as a tuple; one not in ``allowed``, or repeated, is :class:`InvalidParameterError`."""
    if isinstance(names, str):
        raise InvalidParameterError(f"terms must be a sequence of names, not the string {names!r}")
    out: list[str] = []
    for name in names:
        if name not in allowed:
            raise InvalidParameterError(f"unknown term {name!r}; the terms are {', '.join(allowed)}")
        if name in out:
            raise InvalidParameterError(
                f"term {name!r} is given twice; each term has one parameter and may appear once"
            )
        out.append(name)
    return tuple(out)


def term_from_dict(d: Mapping[str, Any]) -> Term:
    """The term a :meth:`Term.to_dict` mapping describes (dispatch on its ``kind``)."""
    if not isinstance(d, Mapping):
        raise InvalidParameterError(f"a term must be a mapping with a 'kind', got {type(d).__name__}")
    kind = d.get("kind")
    if kind not in TERMS:
        raise InvalidParameterError(f"unknown term kind {kind!r}; the terms are {', '.join(TERMS)}")
    return TERMS[str(kind)].from_dict(d)


def core_terms(terms: Iterable[Term]) -> dict[str, float]:
    """``{code name: value}`` (plus each friction's ``<code name>_smoothing``), as the simulation core takes
    them."""
    out: dict[str, float] = {}
    for t in terms:
        if isinstance(t, Distortion):
            raise InvalidParameterError(
                "the distortion term stands for the measured input's own harmonics, which simulate does not "
                "know: simulate the plain plant with the distorted input itself (simulate_input with its "
                "samples) instead"
            )
        out[t.rust_kind] = t.value
        if isinstance(t, Coulomb):
            # "coulomb_smoothing", "coulomb@x_smoothing": the setting of the term at its place.
            out[f"{t.rust_kind}_smoothing"] = t.smoothing
    return out


# One public home: pickles and help() name every class ``bouc_wen_id.terms.<Name>``, as when the registry was
# one file (a pickle written before the split loads after it, and one written after it loads before it).
for _cls in (Place, StartContext, Term, *TERMS.values()):
    _cls.__module__ = __name__
del _cls
placed_kind.__module__ = __name__

"""The terms' common ground: where a term acts (:class:`Place`), what its start guess may look at
(:class:`StartContext`) and the protocol every term class follows (:class:`Term`: one fitted parameter, its
vocabulary as class attributes, its validation, scaling, dict form and siblings at other places).

Part of the registry :mod:`bouc_wen_id.terms` (import from there); the terms themselves are in the modules
beside this one, one per place they act at.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from enum import Enum
from typing import Any, ClassVar, cast

from .._term_at import PlaceAt
from ..errors import InvalidParameterError
from ..validation import real_number

#: The whole real line: the admissible range of a parameter of either sign.
UNBOUNDED = (-math.inf, math.inf)
#: Parameters that are >= 0: a lag, a half-width, a rate of loss; a mass, a damping, a friction level.
NON_NEGATIVE = (0.0, math.inf)


class Place(str, Enum):
    """Where a term acts in the cascade ``u -> G -> x -> hysteresis -> w -> y``.

    A term's place is a field of its class (:attr:`Term.acts_on`, :attr:`Term.places`). A term at a place
    other than its usual one is a sibling class (:meth:`Term.at`) whose code name is the usual one with
    ``@`` and the place's value appended (``"viscous@x"``), composed, never spelled; a new place is one
    member here, its :attr:`label`, one sibling class per term that acts there, and its arm in the models.
    """

    #: Added to, or filtering, the measured output y (an offset, a sensor lag).
    OUTPUT = "output"
    #: Driven by the measured input u, added to the output (a path beside the cascade).
    INPUT = "u"
    #: Inside the Bouc-Wen element: its shape, its input's path or its strength.
    HYSTERESIS = "hysteresis"
    #: Across the hysteretic element, on its own input ``x = G u`` (in parallel with it, as Bouc-Wen's own
    #: elastic term ``alpha k x`` or a damper's dashpot): the term's value is shared, its phase follows G.
    X = "x"

    @property
    def label(self) -> str:
        """How a verdict says where the term acts."""
        return _PLACE_LABELS[self]


_PLACE_LABELS = {
    Place.OUTPUT: "on the measured output y",
    Place.INPUT: "on the measured input u",
    Place.HYSTERESIS: "inside the hysteretic element",
    Place.X: "across the hysteretic element (on x)",
}


def placed_kind(kind: str, place: Place) -> str:
    """The code name of term ``kind`` acting at ``place`` other than its usual one: ``"<kind>@<place>"``."""
    return f"{kind}@{place.value}"


@dataclass(frozen=True)
class StartContext:
    """What a term's start guess may look at, in the diagnosis's scaled units (design.md 10.1).

    ``projection`` is called only by the linear terms: the least-squares value of the term's parameter on
    the current model's residual (its Jacobian column against the residual), which costs one model
    evaluation per experiment.
    """

    #: ``|A_i| = |U_i g_i|``, the latent amplitudes of the current model.
    latent_amplitudes: tuple[float, ...]
    #: The highest tested frequency (rad/s).
    max_frequency: float
    #: The current model's Bouc-Wen parameters.
    beta: float
    gamma: float
    projection: Callable[[], float]
    #: RMS of the current model's residual over every experiment (a two-parameter element's level).
    residual_rms: float = math.nan
    #: ``|U_i|``, the measured input amplitudes (a term on u scales with them; empty: not given).
    input_amplitudes: tuple[float, ...] = ()


@dataclass(frozen=True)
class Term:
    """Base of the physical terms: one fitted parameter, named by :attr:`symbol`.

    Subclasses set the class attributes below and one float field named :attr:`symbol`.
    """

    #: Code name (the key of :data:`~bouc_wen_id.terms.TERMS` and of the Rust core's ``terms`` mapping).
    kind: ClassVar[str] = ""
    #: Symbol of the parameter, also the name of its field.
    symbol: ClassVar[str] = ""
    #: Units of the parameter, a template in ``{y}`` and ``{u}``.
    unit: ClassVar[str] = ""
    #: What the term is, physically (one line).
    description: ClassVar[str] = ""
    #: What leaving it out of a plain fit leaves in the residual (one line).
    signature: ClassVar[str] = ""
    #: The kind the Rust core's ``TermKind`` parses (the code name itself; set by ``__init_subclass__``).
    rust_kind: ClassVar[str] = ""
    #: Human name in verdicts and reports.
    label: ClassVar[str] = ""
    #: Where the term acts (see :class:`Place`)...
    acts_on: ClassVar[Place] = Place.OUTPUT
    #: ... and every place it may act at (the first is :attr:`acts_on`).
    places: ClassVar[tuple[Place, ...]] = ()
    #: Admissible range of the parameter: the value type refuses, and the fits stay within, anything outside.
    bounds: ClassVar[tuple[float, float]] = UNBOUNDED
    #: Physically meaningful range (within :attr:`bounds`): a value outside it is not named as that physics.
    physical: ClassVar[tuple[float, float]] = UNBOUNDED
    #: What a fitted value outside :attr:`physical` would mean (said when the diagnosis declines to name it).
    unphysical: ClassVar[str] = ""
    #: What a value beyond :attr:`physical` that fits most of a misfit suggests (the physics or the recording
    #: error that gives such a value; said by the verdict, diagnosis/bounds_said.py); "" when nothing more
    #: than :attr:`unphysical`.
    beyond: ClassVar[str] = ""
    #: Why the lower bound holds (appended to the error message).
    bound_note: ClassVar[str] = ""
    #: Seen on the averaged steady period (False: only in the period-by-period record, design.md 10.6).
    steady: ClassVar[bool] = True
    #: Among the diagnosis's candidates (False: a library term the diagnosis cannot fit yet).
    diagnosable: ClassVar[bool] = True
    #: The output is linear in the parameter: its start is the projection of the residual on its column.
    linear: ClassVar[bool] = False
    #: The output jumps with each experiment's phase (a step at the reversals of x, 1 % of a radian wide):
    #: the fit's cost is a staircase in the phases, so the diagnosis screens them on a grid first.
    phase_screen: ClassVar[bool] = False
    #: Powers ``(a, b, c)`` of the units: the parameter scales as ``[y]^(a + c mu) [u]^b`` (design.md 10.1).
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)

    #: The code name of the term at its usual place (the same as :attr:`kind` there).
    base_kind: ClassVar[str] = ""
    #: A two-parameter element (Dahl friction) is two terms given together at one place: the first names the
    #: second (:attr:`companion`), the second the first (:attr:`part_of`); the diagnosis adds them as one.
    companion: ClassVar[str] = ""
    part_of: ClassVar[str] = ""

    @classmethod
    def start_pairs(cls, context: StartContext) -> tuple[tuple[float, float], ...]:
        """Starts ``(own value, companion's value)`` of a term with a :attr:`companion`."""
        return ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        base = cls.__mro__[1]
        if "acts_on" in cls.__dict__ and issubclass(base, Term) and base.kind and cls.acts_on != base.acts_on:
            # A sibling at another place: its code name and label are composed from the usual one's.
            cls.base_kind = base.kind
            cls.kind = placed_kind(base.kind, cls.acts_on)
            cls.label = f"{base.label} {cls.acts_on.label}"
            cls.rust_kind = cls.kind
            cls.places = (cls.acts_on, *(p for p in base.places if p != cls.acts_on))
            _SIBLINGS[(base.kind, cls.acts_on)] = cls
            return
        cls.base_kind = cls.kind
        if "rust_kind" not in cls.__dict__:
            cls.rust_kind = cls.kind
        if "places" not in cls.__dict__:
            cls.places = (cls.acts_on,)

    @classmethod
    def place_label(cls) -> str:
        """The label with the place where the term could be at more than one: what a verdict prints
        (``"viscous damping on the measured input u"``; a sibling's label names its place already)."""
        if len(cls.places) < 2 or cls.base_kind != cls.kind:
            return cls.label
        return f"{cls.label} {cls.acts_on.label}"

    @property
    def place(self) -> Place:
        """Where this term acts (:attr:`acts_on`)."""
        return self.acts_on

    #: On the class, the class of this term acting at ``place`` (one of :attr:`places`):
    #: ``Viscous.at(Place.X)(c)``; on an instance, the same term with its value(s) at ``place``:
    #: ``Viscous(0.03).at(Place.X)`` is ``Viscous.at(Place.X)(0.03)`` (:class:`.._term_at.PlaceAt`).
    at: ClassVar[PlaceAt] = PlaceAt()

    @classmethod
    def class_at(cls, place: Place) -> type[Term]:
        """The class of this term acting at ``place`` (the class's :attr:`at`); a named error where the term
        cannot act there."""
        # A sibling's usual class is its parent: ``__init_subclass__`` composed the sibling's names from it.
        base = cls if cls.base_kind == cls.kind else cast("type[Term]", cls.__mro__[1])
        if place == base.acts_on:
            return base
        sibling = _SIBLINGS.get((base.kind, place))
        if sibling is None:
            where = Place(place).label if place in tuple(Place) else f"at {place!r} (not a Place)"
            raise InvalidParameterError(
                f"{base.kind} cannot act {where}; its places are {', '.join(p.label for p in base.places)}"
            )
        return sibling

    def placed(self, place: Place) -> Term:
        """This term with its value(s) at ``place`` (the instance's :attr:`at`)."""
        cls = self.class_at(place)
        return cls(**{f.name: getattr(self, f.name) for f in fields(cls)})

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, real_number(f"{self.kind}.{f.name}", getattr(self, f.name)))
        lo, hi = self.bounds
        v = self.value
        if not lo <= v <= hi:
            unit = "" if "{" in self.unit or not self.unit else f" {self.unit}"
            rule = f">= {lo:g}" if math.isinf(hi) else f"in [{lo:g}, {hi:g}]"
            raise InvalidParameterError(
                f"{self.kind} {self.symbol} = {v}{unit} must be {rule}{self.bound_note}"
            )
        self._check()

    def _check(self) -> None:
        """Extra admissibility of the parameter (after the finiteness and range checks)."""

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        """Start values of the parameter when the diagnosis adds the term to a model (scaled units)."""
        if cls.linear:
            return (context.projection(), 0.0)
        return (0.0,)

    @classmethod
    def scale_factor(cls, y: float, u: float, mu: float) -> float:
        """Physical value per unit of scaled value, for data scaled by ``y`` and ``u`` (:attr:`scaling`)."""
        a, b, c = cls.scaling
        return float(y ** (a + c * mu) / u ** (-b))

    @property
    def value(self) -> float:
        """The parameter's value (units :meth:`units`)."""
        return float(getattr(self, self.symbol))

    def with_value(self, value: float) -> Term:
        """The same term with its parameter set to ``value`` (validated)."""
        return replace(self, **{self.symbol: value})

    @classmethod
    def units(cls, y: str = "[y]", u: str = "[u]") -> str:
        """The parameter's units with the output's unit ``y`` and the input's unit ``u`` filled in."""
        return cls.unit.format(y=y, u=u)

    def normalized(self, alpha: float) -> Term:
        """The term of the equivalent plant with alpha = 1 (``G -> alpha G``); output terms are unchanged."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": code name, field: value, ...}`` (JSON-ready)."""
        out: dict[str, Any] = {"kind": self.kind}
        for f in fields(self):
            out[f.name] = getattr(self, f.name)
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Term:
        """Inverse of :meth:`to_dict` (the ``kind`` must be this class's, when present)."""
        kind = d.get("kind", cls.kind)
        if kind != cls.kind:
            raise InvalidParameterError(f"a {cls.__name__} needs kind {cls.kind!r}, got {kind!r}")
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names - {"kind"})
        if unknown:
            raise InvalidParameterError(f"{cls.kind}: unknown field(s) {unknown}; expected {sorted(names)}")
        if cls.symbol not in d:
            raise InvalidParameterError(f"{cls.kind}: the parameter {cls.symbol!r} is missing")
        return cls(**{k: d[k] for k in names if k in d})


#: ``(usual code name, place) -> sibling class`` of every term at a place other than its usual one.
_SIBLINGS: dict[tuple[str, Place], type[Term]] = {}

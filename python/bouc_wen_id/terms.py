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
augmented model's names and the JSON all derive from it. A new term is one class here (plus its Rust match
arm, its oracle and its tests).

The units are templates in ``{y}`` (the output's unit) and ``{u}`` (the input's); fill them with
:meth:`Term.units`.  ``x`` has the units of ``y`` in the identified (alpha = 1) model, so play is in
``{y}`` there.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from enum import Enum
from typing import Any, ClassVar

from .errors import InvalidParameterError
from .validation import real_number

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

#: Default ``eps`` of the smoothed Coulomb sign: 1 % of the peak input velocity (design.md 9.1).
COULOMB_SMOOTHING = 0.01

#: Largest admissible ``eps``: beyond half the peak velocity the ``tanh`` no longer resembles a sign.
COULOMB_SMOOTHING_MAX = 0.5

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

    #: Code name (the key of :data:`TERMS` and of the Rust core's ``terms`` mapping).
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

    @classmethod
    def at(cls, place: Place) -> type[Term]:
        """The class of this term acting at ``place`` (one of :attr:`places`): ``Viscous.at(Place.X)(c)``."""
        base = TERMS.get(cls.base_kind, cls)
        if place == base.acts_on:
            return base
        sibling = _SIBLINGS.get((base.kind, place))
        if sibling is None:
            where = Place(place).label if place in tuple(Place) else f"at {place!r} (not a Place)"
            raise InvalidParameterError(
                f"{base.kind} cannot act {where}; its places are {', '.join(p.label for p in base.places)}"
            )
        return sibling

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

#: The places of the mechanical terms: on the measured input u, and across the hysteretic element on x.
MECHANICAL_PLACES = (Place.INPUT, Place.X)


@dataclass(frozen=True)
class Offset(Term):
    """Output offset ``y0``: a constant added to the measured output (sensor zero, preload)."""

    y0: float

    kind: ClassVar[str] = "offset"
    symbol: ClassVar[str] = "y0"
    unit: ClassVar[str] = "{y}"
    description: ClassVar[str] = "constant output offset (sensor zero, static preload)"
    signature: ClassVar[str] = "a constant residual: the loop is shifted up or down as a whole (DC)"
    label: ClassVar[str] = "output offset"
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, 0.0, 0.0)
    # Physical range: any sign (a sensor zero or a static preload either way): UNBOUNDED.


@dataclass(frozen=True)
class Stiffness(Term):
    """Parallel stiffness ``k``: ``k u`` added to the output (a spring beside the hysteresis)."""

    k: float

    kind: ClassVar[str] = "stiffness"
    symbol: ClassVar[str] = "k"
    unit: ClassVar[str] = "{y}/{u}"
    description: ClassVar[str] = "elastic force proportional to the input, in parallel with the hysteresis"
    signature: ClassVar[str] = (
        "a residual in phase with u at every frequency: the loop is tilted, not saturating at large u"
    )
    label: ClassVar[str] = "parallel stiffness"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, -1.0, 0.0)
    # Physical range (issue 18): a passive spring stores energy, its force follows its displacement, so
    # k >= 0 at both places. On u it is measured in the recording's own sign convention (y rising with u at
    # low frequency, as a force with a displacement; the identified G's gain is then positive); on x the
    # sign is fixed by the model itself (x = G u in units of y, w rising with x), so k x adds to the element's
    # own elastic force (Bouc-Wen's alpha k x, alpha in [0, 1], k > 0). A negative k is a softening: the
    # loop's slope falls with amplitude beyond what the saturating element gives, which is the hysteresis'
    # own shape (a post-yield slope, a saturation other than Bouc-Wen's), a strength that falls with
    # amplitude (degradation) or a |G| that trades with it below saturation -- not a spring.
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = (
        "a negative stiffness: a softening no passive spring gives (the loop's slope falling with "
        "amplitude: the hysteresis' own saturation shape, a strength falling with amplitude, or |G| "
        "trading with it below saturation)"
    )


@dataclass(frozen=True)
class Viscous(Term):
    """Viscous damping ``c``: ``c udot`` added to the output (a dashpot beside the hysteresis)."""

    c: float

    kind: ClassVar[str] = "viscous"
    symbol: ClassVar[str] = "c"
    unit: ClassVar[str] = "{y} s/{u}"
    description: ClassVar[str] = "viscous force proportional to the input velocity (dashpot)"
    signature: ClassVar[str] = "a residual in quadrature with u, growing as omega: loops widen with frequency"
    label: ClassVar[str] = "viscous damping"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative damping (energy supplied, not dissipated)"
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, -1.0, 0.0)


@dataclass(frozen=True)
class Inertia(Term):
    """Inertia ``m``: ``m uddot`` added to the output (a moving mass seen by the force sensor)."""

    m: float

    kind: ClassVar[str] = "inertia"
    symbol: ClassVar[str] = "m"
    unit: ClassVar[str] = "{y} s^2/{u}"
    description: ClassVar[str] = "inertial force of a moving mass, proportional to the input acceleration"
    signature: ClassVar[str] = (
        "a residual in antiphase with u growing as omega^2: the loop tilts down at high frequency"
    )
    label: ClassVar[str] = "inertia"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative mass"
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, -1.0, 0.0)


@dataclass(frozen=True)
class Coulomb(Term):
    """Dry (Coulomb) friction ``f``: ``f tanh(udot / (eps Vmax))``, a sign smoothed over ``eps Vmax``.

    ``Vmax`` is the peak input velocity (``|U| omega`` for a sine); ``smoothing`` is ``eps``, fixed, in
    ``(0, 0.5]``.
    """

    f: float
    smoothing: float = COULOMB_SMOOTHING

    kind: ClassVar[str] = "coulomb"
    symbol: ClassVar[str] = "f"
    unit: ClassVar[str] = "{y}"
    description: ClassVar[str] = "dry friction of constant level opposing the input velocity"
    signature: ClassVar[str] = (
        "a square wave in phase with udot: steps at each reversal of u, odd harmonics falling as 1/k"
    )
    label: ClassVar[str] = "dry (Coulomb) friction"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative friction (energy supplied at every reversal)"
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, 0.0, 0.0)

    def _check(self) -> None:
        if not 0.0 < self.smoothing <= COULOMB_SMOOTHING_MAX:
            raise InvalidParameterError(
                f"coulomb.smoothing eps = {self.smoothing} must be in (0, {COULOMB_SMOOTHING_MAX}]"
            )


@dataclass(frozen=True)
class SensorLag(Term):
    """First-order output (sensor) lag ``tau``: the output is seen through ``1/(tau s + 1)``."""

    tau: float

    kind: ClassVar[str] = "sensor_lag"
    symbol: ClassVar[str] = "tau"
    unit: ClassVar[str] = "s"
    description: ClassVar[str] = "first-order lag of the output sensor or its filter, 1/(tau s + 1)"
    signature: ClassVar[str] = (
        "the whole output delayed by about tau: a residual like -tau ydot, growing with frequency"
    )
    label: ClassVar[str] = "sensor lag"
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative lag (an output ahead of its cause)"

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # 1 % and 10 % of a radian of lag at the highest frequency.
        return tuple(f / context.max_frequency for f in (0.01, 0.1))


@dataclass(frozen=True)
class Asymmetry(Term):
    """Asymmetry ``delta`` of the Bouc-Wen element (the ``sgn(w)`` term of Song & Der Kiureghian).

    The loop saturates at ``(beta + gamma + delta)^(-1/mu)`` above and ``-(beta + gamma - delta)^(-1/mu)``
    below (alpha = 1); the plant requires ``beta + gamma > |delta|``.
    """

    delta: float

    kind: ClassVar[str] = "asymmetry"
    symbol: ClassVar[str] = "delta"
    unit: ClassVar[str] = "1/{y}^mu"
    description: ClassVar[str] = "different saturation levels of the hysteresis in the two directions"
    signature: ClassVar[str] = (
        "upper and lower branches saturate at different levels: even harmonics and a DC shift"
    )
    label: ClassVar[str] = "asymmetry"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, -1.0)
    # Physical range: either sign (which branch saturates lower); the bound |delta| < beta + gamma that
    # keeps both branches saturating depends on the fit and is the model's admissibility, checked there.

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # Symmetric, and 30 % of beta + gamma either way.
        bg = context.beta + context.gamma
        return tuple(v * bg for v in (0.0, 0.3, -0.3))

    def normalized(self, alpha: float) -> Term:
        return Asymmetry(self.delta / alpha)


@dataclass(frozen=True)
class Play(Term):
    """Play (backlash) of half-width ``b`` between the linear part and the hysteresis: ``xp = Play_b[x]``.

    ``b`` is in units of ``x`` (those of ``y`` in the identified alpha = 1 model); per experiment it must
    stay below the latent amplitude ``|A|``.
    """

    b: float

    kind: ClassVar[str] = "play"
    symbol: ClassVar[str] = "b"
    unit: ClassVar[str] = "{y}"
    description: ClassVar[str] = "backlash (dead travel of 2b) before the hysteresis, after each reversal"
    signature: ClassVar[str] = (
        "flat stretches after each reversal: the output dwells for 2b of travel before it follows"
    )
    label: ClassVar[str] = "play (backlash)"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative play"
    bound_note: ClassVar[str] = " (it is a half-width)"
    scaling: ClassVar[tuple[float, float, float]] = (1.0, 0.0, 0.0)

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # 1, 10 and 30 % of the smallest latent amplitude (it must stay below every one).
        return tuple(f * min(context.latent_amplitudes) for f in (0.01, 0.1, 0.3))

    def normalized(self, alpha: float) -> Term:
        return Play(self.b * alpha)


@dataclass(frozen=True)
class Degradation(Term):
    """Strength degradation with dissipated energy (Baber & Noori 1985): ``nu = 1 + delta_nu e``.

    ``e = int w dxp`` is the hysteretic energy dissipated since the start, and ``nu`` multiplies the
    beta, gamma (and delta) terms of the rate, so the loop's saturation level falls as
    ``(alpha / (nu (beta + gamma)))^(1/mu)``. ``delta_nu >= 0`` in ``1/({y} x)``: ``1/{y}^2`` in the
    identified (alpha = 1) model, where x has the units of y. The steady averaged period cannot see it
    (to first order the mean loop is the loop at the mean strength); the diagnosis fits it from the
    period-by-period record (design.md 10.6).
    """

    delta_nu: float

    kind: ClassVar[str] = "degradation"
    symbol: ClassVar[str] = "delta_nu"
    unit: ClassVar[str] = "1/{y}^2"
    description: ClassVar[str] = (
        "hysteretic strength falling with the energy dissipated (Baber-Noori strength degradation)"
    )
    signature: ClassVar[str] = (
        "a loop that drifts from period to period, faster for loops dissipating more energy (larger "
        "amplitudes): the peak of w shrinks; the averaged loop is unchanged to first order"
    )
    label: ClassVar[str] = "degradation"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    bound_note: ClassVar[str] = " (the strength falls with dissipated energy)"
    steady: ClassVar[bool] = False
    scaling: ClassVar[tuple[float, float, float]] = (-2.0, 0.0, 0.0)

    def normalized(self, alpha: float) -> Term:
        # e = int w dx grows by alpha under x -> alpha x (G -> alpha G), so delta_nu shrinks by it.
        return Degradation(self.delta_nu / alpha)


@dataclass(frozen=True)
class StiffnessDegradation(Term):
    """Stiffness degradation with dissipated energy (Baber & Noori 1985): the rate over ``eta``.

    ``eta = 1 + delta_eta e``, ``e = int w dxp`` as for :class:`Degradation`; ``eta`` divides the whole
    Bouc-Wen rate (alpha included), so the saturation level ``(alpha / (beta + gamma))^(1/mu)`` stays and
    is reached over a longer travel: the loop softens. To first order a block at ``eta`` is the steady loop
    with its gain ``|G|`` divided by ``eta``, so the diagnosis fits it from the period-by-period record beside
    ``delta_nu`` (design.md 10.6).
    """

    delta_eta: float

    kind: ClassVar[str] = "stiffness_degradation"
    symbol: ClassVar[str] = "delta_eta"
    unit: ClassVar[str] = "1/{y}^2"
    description: ClassVar[str] = (
        "hysteretic stiffness falling with the energy dissipated (Baber-Noori stiffness degradation)"
    )
    signature: ClassVar[str] = (
        "a loop that drifts from period to period, faster for loops dissipating more energy: the loop "
        "softens (its phase lags further and, below saturation, its amplitude falls) while the peak of w "
        "stays"
    )
    label: ClassVar[str] = "stiffness degradation"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    bound_note: ClassVar[str] = " (the stiffness falls with dissipated energy)"
    steady: ClassVar[bool] = False
    scaling: ClassVar[tuple[float, float, float]] = (-2.0, 0.0, 0.0)

    def normalized(self, alpha: float) -> Term:
        # e grows by alpha under x -> alpha x, as for Degradation.
        return StiffnessDegradation(self.delta_eta / alpha)


#: Pinching's fixed shape (Foliente 1995): the band's centre ``q`` and width ``zeta2``, fractions of the
#: saturation level ``w_u = (alpha / (beta + gamma))^(1/mu)``.
PINCHING_CENTRE = 0.1
PINCHING_WIDTH = 0.2


@dataclass(frozen=True)
class Pinching(Term):
    """Pinching (Baber & Noori 1986, Foliente 1995): the rate times Foliente's ``h(w, sgn xdot)``.

    ``h = 1 - zeta1 exp(-(w sgn(xdot) - q w_u)^2 / (zeta2 w_u)^2)``.

    ``zeta1`` in ``[0, 1)`` is the share of the rate taken out at the band's centre; the shape is fixed at
    ``q = PINCHING_CENTRE``, ``zeta2 = PINCHING_WIDTH`` (fractions of the virgin saturation level ``w_u``).
    Rate independent: it slows w in a band just past its zero crossing after each reversal (slip), so its
    steady loop is the path loop of design.md 9.2 with ``h`` times the factor, fitted like play.
    """

    zeta1: float

    kind: ClassVar[str] = "pinching"
    symbol: ClassVar[str] = "zeta1"
    unit: ClassVar[str] = ""  # dimensionless
    description: ClassVar[str] = "slip of the hysteresis near zero force after each reversal (pinched loop)"
    signature: ClassVar[str] = (
        "localised to a band of w on each branch just past the zero crossing after a reversal: excess odd "
        "harmonics 3, 5; a loop-area deficit; only above an amplitude threshold (the band must be crossed)"
    )
    label: ClassVar[str] = "pinching"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    bound_note: ClassVar[str] = " (the share of the rate taken out)"

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # None, a light and a marked pinch (the fit stays below PINCHING_MAX = 0.95).
        return (0.0, 0.2, 0.5)

    def _check(self) -> None:
        if self.zeta1 >= 1.0:
            raise InvalidParameterError(
                f"pinching zeta1 = {self.zeta1} must be < 1 (at 1 the loop would stop at the band's centre)"
            )


@dataclass(frozen=True)
class Distortion(Term):
    """A measured, non-sinusoidal input (design.md 9.5): ``x = A xi(theta - phi)``, ``xi = cos + lam d``.

    ``d`` is the input's own normalised harmonics (``k >= 2``, relative to its fundamental), measured per
    experiment; ``lam`` scales them (1: the measured waveform drives the hysteresis; 0: the pure sine the
    plain model assumes). G is taken as quasi-static over the harmonics that matter (flat gain, linear
    phase). The diagnosis fits it on averaged periods; ``simulate`` takes the true input itself instead
    (a sampled input), so a plant carrying this term is not simulated.
    """

    lam: float

    kind: ClassVar[str] = "distortion"
    symbol: ClassVar[str] = "lam"
    unit: ClassVar[str] = ""  # dimensionless
    description: ClassVar[str] = "the measured input's own harmonics (a distorted actuator) drive the model"
    signature: ClassVar[str] = (
        "the input's harmonics reflected in the output: the loop driven by the distortion, at the "
        "harmonics the input carries"
    )
    label: ClassVar[str] = "measured input waveform"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    # Physical range: lam >= 0 (the measured harmonics drive the hysteresis, scaled; 1 when G is flat over
    # them). A negative lam drives it with the harmonics inverted: G's assumption (design.md 9.5) fails.
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = (
        "a negative input-waveform scale: the harmonics drive the hysteresis inverted, so G's assumed "
        "shape over the harmonics (flat gain, linear phase) fails"
    )

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # lambda = 1: the measured waveform drives the model (the expected value under the quasi-static
        # assumption of design.md 9.5); 0: the plain model's sine.
        return (1.0, 0.0)


@dataclass(frozen=True)
class SeriesDashpot(Term):
    """Spencer's series dashpot (Spencer, Dyke, Sain & Carlson, J. Eng. Mech. 123(3), 1997): the
    hysteretic element behind a dashpot in series, driven by its own travel ``d = x - q``.

    The dashpot carries the element's force, ``c1 qdot = w``, so with ``rho = 1/c1``::

        ddot = xdot - rho w,    wdot = ddot [1 - |w|^mu (beta sgn(ddot w) + gamma + delta sgn(w))]

    and the output is ``w`` (plus the other terms): in the elastic range ``w`` is ``x`` seen through the
    high-pass ``s/(s + rho)`` (a time constant ``1/rho``), in saturation the dashpot creeps at
    ``rho w_u``, so the force rolls off below the velocity ``rho w_u`` (Spencer's low-velocity roll-off).
    ``rho`` is in ``1/s`` in the identified (alpha = 1) model (x in units of y); 0 is no dashpot.
    Spencer's other parameters are the library's: ``alpha``, ``A`` go into ``|G|`` and the alpha = 1
    normalisation, ``k1`` is ``stiffness@x``, ``-k1 x0`` the offset, ``c0`` (with ``c0 << c1``)
    ``viscous@x``; ``k0`` is left out (docs/diagnosis.md, "Series dashpot").
    """

    rho: float

    kind: ClassVar[str] = "series_dashpot"
    symbol: ClassVar[str] = "rho"
    unit: ClassVar[str] = "1/s"  # [x]/([y] s), x in units of y in the identified model
    description: ClassVar[str] = (
        "a dashpot in series with the hysteretic element (Spencer's MR-damper model): the element is "
        "driven by its own travel, which creeps under its force"
    )
    signature: ClassVar[str] = (
        "a rate-dependent loop: the force rolls off at low velocity (rounded corners after each reversal, "
        "a saturation that leans back with the creep), a lag of w behind x that shrinks as 1/omega; "
        "harmonics 1, 3, 5 falling with frequency"
    )
    label: ClassVar[str] = "series dashpot"
    acts_on: ClassVar[Place] = Place.HYSTERESIS
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative series dashpot (a creep that supplies energy)"
    bound_note: ClassVar[str] = " (the inverse of the series dashpot's coefficient; 0: no dashpot)"
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # The creep rate rho (times w_u ~ 1 in the scaled units) at 0.1 and 1 times the highest frequency:
        # the force rolls off below the velocity rho w_u, about |A| omega where the term is seen.
        return tuple(f * context.max_frequency for f in (0.1, 1.0))

    def normalized(self, alpha: float) -> Term:
        # qdot = rho w is in units of x: under x -> alpha x (G -> alpha G) rho grows by alpha.
        return SeriesDashpot(self.rho * alpha)


@dataclass(frozen=True)
class DahlSigma(Term):
    """Dahl friction's pre-sliding stiffness ``sigma`` (dF/dv after a reversal), given with :class:`Dahl`."""

    sigma: float

    kind: ClassVar[str] = "dahl_sigma"
    symbol: ClassVar[str] = "sigma"
    unit: ClassVar[str] = "{y}/{u}"
    description: ClassVar[str] = "pre-sliding stiffness of the Dahl friction (its slope after each reversal)"
    signature: ClassVar[str] = "with the Dahl friction's level: how sharply the friction turns at a reversal"
    label: ClassVar[str] = "Dahl pre-sliding stiffness"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative pre-sliding stiffness"
    bound_note: ClassVar[str] = " (the friction's stiffness after a reversal)"
    scaling: ClassVar[tuple[float, float, float]] = (1.0, -1.0, 0.0)
    part_of: ClassVar[str] = "dahl"


@dataclass(frozen=True)
class Dahl(Term):
    """Dahl friction (Dahl 1968; LuGre's pre-sliding limit): ``F' = sigma v' (1 - sgn(v') F / Fc)``.

    ``v`` is the travel at its place (the measured input u, or x across the hysteretic element); ``F`` is
    added to the output. Two parameters, two terms given together: this one's level ``fc`` (a force, in
    [y]) and :class:`DahlSigma`'s pre-sliding stiffness ``sigma``. ``sigma -> inf`` is dry (Coulomb)
    friction of level ``Fc``, ``Fc -> inf`` a spring of stiffness ``sigma``; ``Fc = 0`` is no friction.
    Under a sine its steady loop is closed form (``rust/dahl.rs``): from a reversal at ``v = A`` the force
    falls as ``-Fc + (F_top + Fc) exp(-sigma (A - v) / Fc)``, ``F_top = Fc tanh(sigma A / Fc)``.
    """

    fc: float

    kind: ClassVar[str] = "dahl"
    symbol: ClassVar[str] = "fc"
    unit: ClassVar[str] = "{y}"
    description: ClassVar[str] = "pre-sliding (Dahl) friction: turns over a short travel, saturates at Fc"
    signature: ClassVar[str] = (
        "a small parallel loop: a spring's slope after each reversal, a level Fc once sliding; spring-like "
        "at small amplitude, dry-friction-like at large"
    )
    label: ClassVar[str] = "Dahl friction"
    acts_on: ClassVar[Place] = Place.INPUT
    places: ClassVar[tuple[Place, ...]] = MECHANICAL_PLACES
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative friction level"
    bound_note: ClassVar[str] = " (the friction level; 0: no friction)"
    scaling: ClassVar[tuple[float, float, float]] = (1.0, 0.0, 0.0)
    companion: ClassVar[str] = DahlSigma.kind
    limits: ClassVar[tuple[str, ...]] = (Stiffness.kind, Coulomb.kind)  # Fc -> inf, sigma -> inf: simpler

    #: Start shapes ``sigma A / Fc`` (A: the median travel amplitude): spring-like, turning, sliding.
    START_SHAPES: ClassVar[tuple[float, ...]] = (0.3, 3.0, 30.0)

    @classmethod
    def start_pairs(cls, context: StartContext) -> tuple[tuple[float, float], ...]:
        # Top Fc tanh(r) at 2 (1 + r/2) residual RMS (r in START_SHAPES): plain Bouc-Wen absorbs a sharp loop.
        amps = context.latent_amplitudes if cls.acts_on == Place.X else context.input_amplitudes
        amp = float(sorted(amps)[len(amps) // 2]) if amps else 1.0
        rms = context.residual_rms if context.residual_rms > 0 else 0.1  # nan: not given
        fcs = [2.0 * rms * (1.0 + 0.5 * r) / math.tanh(r) for r in cls.START_SHAPES]
        return tuple((fc, r * fc / max(amp, 1e-300)) for fc, r in zip(fcs, cls.START_SHAPES))


@dataclass(frozen=True)
class StiffnessX(Stiffness):
    """Stiffness across the hysteretic element: ``k x`` (Bouc-Wen's own elastic term ``alpha k x``).

    ``x`` has the units of ``y`` in the identified (alpha = 1) model, so ``k`` is dimensionless
    (``[y]/[y]``); its phase follows each experiment's G.
    """

    acts_on: ClassVar[Place] = Place.X
    unit: ClassVar[str] = ""  # [y]/[x], x in units of y: dimensionless
    description: ClassVar[str] = "elastic force proportional to the hysteresis' input x, in parallel with it"
    signature: ClassVar[str] = (
        "a residual in phase with x (lagging u as G does): the loop tilted along x; below saturation it "
        "trades with |G|"
    )
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)

    def normalized(self, alpha: float) -> Term:
        # x -> alpha x under G -> alpha G: k x = (k / alpha) (alpha x).
        return StiffnessX(self.k / alpha)


@dataclass(frozen=True)
class ViscousX(Viscous):
    """Viscous damping across the hysteretic element: ``c xdot`` (a dashpot beside it), ``c`` in s."""

    acts_on: ClassVar[Place] = Place.X
    unit: ClassVar[str] = "s"  # [y] s/[x], x in units of y
    description: ClassVar[str] = "viscous force proportional to the hysteresis' input velocity xdot"
    signature: ClassVar[str] = (
        "a residual in quadrature with x (not with u: its phase follows G), growing as omega"
    )
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)

    def normalized(self, alpha: float) -> Term:
        return ViscousX(self.c / alpha)


@dataclass(frozen=True)
class InertiaX(Inertia):
    """Inertia across the hysteretic element: ``m xddot``, ``m`` in s^2 (x in units of y)."""

    acts_on: ClassVar[Place] = Place.X
    unit: ClassVar[str] = "s^2"  # [y] s^2/[x], x in units of y
    description: ClassVar[str] = "inertial force proportional to the hysteresis' input acceleration xddot"
    signature: ClassVar[str] = "a residual in antiphase with x (its phase follows G), growing as omega^2"
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)

    def normalized(self, alpha: float) -> Term:
        return InertiaX(self.m / alpha)


@dataclass(frozen=True)
class CoulombX(Coulomb):
    """Dry friction across the hysteretic element: ``f tanh(xdot / (eps |A| omega))``, ``f`` in [y]."""

    acts_on: ClassVar[Place] = Place.X
    phase_screen: ClassVar[bool] = True
    description: ClassVar[str] = "dry friction of constant level opposing the hysteresis' input velocity"
    signature: ClassVar[str] = "a square wave in phase with xdot: steps at each reversal of x (not of u)"

    def normalized(self, alpha: float) -> Term:
        return self


@dataclass(frozen=True)
class DahlSigmaX(DahlSigma):
    """Dahl friction's pre-sliding stiffness across the hysteretic element (x in units of y: no unit)."""

    acts_on: ClassVar[Place] = Place.X
    unit: ClassVar[str] = ""  # [y]/[x], x in units of y
    scaling: ClassVar[tuple[float, float, float]] = (0.0, 0.0, 0.0)
    part_of: ClassVar[str] = placed_kind(Dahl.kind, Place.X)

    def normalized(self, alpha: float) -> Term:  # sigma x = (sigma / alpha) (alpha x)
        return DahlSigmaX(self.sigma / alpha)


@dataclass(frozen=True)
class DahlX(Dahl):
    """Dahl friction across the hysteretic element, on x: ``F' = sigma xdot (1 - sgn(xdot) F / Fc)``."""

    acts_on: ClassVar[Place] = Place.X
    signature: ClassVar[str] = "as on u, its reversals following x: near a spring on x, or dry friction on x"
    companion: ClassVar[str] = DahlSigmaX.kind
    limits: ClassVar[tuple[str, ...]] = (StiffnessX.kind, CoulombX.kind)


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

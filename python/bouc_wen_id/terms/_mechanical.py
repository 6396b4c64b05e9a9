"""The mechanical terms: forces in parallel with the hysteresis, acting on the measured input u or, as sibling
classes, across the hysteretic element on its own input x (:data:`MECHANICAL_PLACES`): parallel stiffness,
viscous damping, inertia, dry (Coulomb) friction and Dahl friction (two terms given together).

Part of the registry :mod:`bouc_wen_id.terms` (import from there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from ..errors import InvalidParameterError
from ._base import NON_NEGATIVE, Place, StartContext, Term, placed_kind

#: Default ``eps`` of the smoothed Coulomb sign: 1 % of the peak input velocity (design.md 9.1).
COULOMB_SMOOTHING = 0.01

#: Largest admissible ``eps``: beyond half the peak velocity the ``tanh`` no longer resembles a sign.
COULOMB_SMOOTHING_MAX = 0.5

#: The places of the mechanical terms: on the measured input u, and across the hysteretic element on x.
MECHANICAL_PLACES = (Place.INPUT, Place.X)


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
    beyond: ClassVar[str] = (
        "a negative stiffness in parallel: a geometric (P-Delta) or magnetic negative-stiffness mechanism, "
        "or an input recorded with the wrong sign or scale"
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
    beyond: ClassVar[str] = (
        "energy supplied each cycle: an active element (a controlled actuator in the loop), or a phase error "
        "between the recorded channels (a lag of u against y, or a negative stiffness seen through G's "
        "phase), or a loop whose shape changes with the rate (outside the model)"
    )
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
    beyond: ClassVar[str] = (
        "a negative mass: at one frequency a stiffness of the same sign (-m w^2 acts as +k), or an input "
        "recorded with the wrong sign or scale"
    )
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

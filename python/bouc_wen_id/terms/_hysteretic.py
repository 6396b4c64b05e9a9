"""The terms inside the hysteretic element (:attr:`Place.HYSTERESIS`): its shape (asymmetry, pinching), its
input's path (play, a measured non-sinusoidal input, a series dashpot) and its strength drifting with the
energy dissipated (strength and stiffness degradation, seen only in the period-by-period record).

Part of the registry :mod:`bouc_wen_id.terms` (import from there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..errors import InvalidParameterError
from ._base import NON_NEGATIVE, Place, StartContext, Term


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

    The energy's origin (``e = 0``, ``nu = 1``): each experiment starts virgin at the first of its
    declared settling periods (a Recording's first sample when those periods are in it; ``settle_periods``
    whole periods before its steady stretch), each experiment a specimen of its own; when the diagnosis
    fits unrecorded ages (diagnosis/age.py) the origin is the youngest experiment's first recorded
    period. A model whose energy counts from ``e0`` earlier (an unrecorded settling, earlier runs) has
    ``nu = (1 + d e0)(1 + d/(1 + d e0) e)``: the first factor goes into beta and gamma, and its
    ``d = delta_nu / (1 - delta_nu e0)``.
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

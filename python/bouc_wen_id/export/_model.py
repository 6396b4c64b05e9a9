"""The plant in the form every exporter writes out: the realisation of G and one value per term.

The exporters (:mod:`._nlsys`, :mod:`._c`) reproduce the library's time-domain simulator
(:func:`bouc_wen_id.simulate_input`, docs/design.md sections 1 and 9.4): the controllable canonical form
``xsdot = A xs + B v``, ``x = C xs + D v`` of G with ``v(t) = u(t - delay)``, the generalised Bouc-Wen rate
with the terms that change it, and the output terms.  :func:`flatten` checks once what they can export: the
terms ``simulate_input`` simulates, and nothing else (a measured-input distortion or a term acting on x is
refused by name, as the simulator refuses it).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..terms import (
    COULOMB_SMOOTHING,
    PINCHING_CENTRE,
    PINCHING_WIDTH,
    TERMS,
    Coulomb,
    Distortion,
    Place,
    SeriesDashpot,
    Term,
    core_terms,
)
from ..validation import check_transfer_function

__all__ = ["Flat", "EXPORTED", "flatten", "realize", "PLAY_ENGAGE_RTOL", "PINCHING_CENTRE", "PINCHING_WIDTH"]

FloatArray = NDArray[np.float64]

#: Relative slack of the play's engagement test (docs/design.md 9.4; the simulator's own constant).
PLAY_ENGAGE_RTOL = 1e-12


class Flat(NamedTuple):
    """A plant as the simulator integrates it; every absent term is 0, as in the simulator.

    The term fields are named by the terms' symbols (:attr:`Term.symbol`), so a term's value lands in
    ``getattr(flat, term.symbol)``.
    """

    #: Monic denominator ``a_1..a_n`` (companion first row ``-a``), output row ``crow``, feed-through
    #: ``dfeed``.
    a: FloatArray
    crow: FloatArray
    dfeed: float
    delay: float
    alpha: float
    beta: float
    gamma: float
    mu: float
    w0: float
    y0: float = 0.0
    k: float = 0.0
    c: float = 0.0
    m: float = 0.0
    f: float = 0.0
    #: ``eps`` of the smoothed Coulomb sign (the term's own, or the library default when absent).
    smoothing: float = COULOMB_SMOOTHING
    tau: float = 0.0
    delta: float = 0.0
    b: float = 0.0
    delta_nu: float = 0.0
    delta_eta: float = 0.0
    zeta1: float = 0.0

    @property
    def order(self) -> int:
        return int(self.a.size)

    @property
    def has_energy(self) -> bool:
        """The dissipated energy is a state (a degradation of strength or stiffness)."""
        return self.delta_nu > 0.0 or self.delta_eta > 0.0

    @property
    def has_play(self) -> bool:
        return self.b > 0.0

    @property
    def has_lag(self) -> bool:
        return self.tau > 0.0

    @property
    def w_u(self) -> float:
        """The virgin saturation level ``(alpha / (beta + gamma))^(1/mu)`` (pinching's band scale)."""
        return float((self.alpha / (self.beta + self.gamma)) ** (1.0 / self.mu))


#: The term classes the exporters write: the registry's terms at their usual place, less the input distortion
#: (a term on x is a subclass of its usual class, with ``acts_on`` = x, and not here).
EXPORTED: tuple[type[Term], ...] = tuple(
    cls for cls in TERMS.values() if cls not in (Distortion, SeriesDashpot) and cls.acts_on != Place.X
)


def realize(num: FloatArray, den: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    """``(a, c, d)`` of the controllable canonical form, written as the simulator writes it (design.md 1)."""
    n = den.size - 1
    an = den / den[0]
    bn = np.concatenate([np.zeros(n + 1 - num.size), num]) / den[0]
    d = float(bn[0])
    return an[1:].astype(np.float64), (bn[1:] - d * an[1:]).astype(np.float64), d


def flatten(plant: WienerPlant, what: str) -> Flat:
    """``plant`` as :class:`Flat`; ``what`` names the exporter in the errors.

    Raises
    ------
    InvalidParameterError
        Not a :class:`WienerPlant`; a term the time-domain simulator does not simulate (the measured-input
        distortion, a term on x): the exporters write the model ``simulate_input`` simulates, no other.
    """
    if not isinstance(plant, WienerPlant):
        raise InvalidParameterError(f"{what} needs a WienerPlant, got {type(plant).__name__}")
    try:
        core_terms(plant.terms)  # the simulator's own refusals, word for word
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"{what}: {exc}") from None
    values: dict[str, float] = {}
    for t in plant.terms:
        if type(t) not in EXPORTED or t.place == Place.X:
            raise InvalidParameterError(
                f"{what}: the term {t.kind!r} ({t.label}) has no exporter; the exporters write the terms "
                f"the time-domain simulator has ({', '.join(c.kind for c in EXPORTED)})"
            )
        values[t.symbol] = t.value
        if isinstance(t, Coulomb):
            values["smoothing"] = t.smoothing
    num, den, delay = check_transfer_function(plant.linear.num, plant.linear.den, plant.linear.delay)
    a, c, d = realize(num, den)
    h = plant.hysteresis
    return Flat(a, c, d, delay, h.alpha, h.beta, h.gamma, h.mu, h.w0, **values)

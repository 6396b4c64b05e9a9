"""The plant in the form every exporter writes out: the realisation of G and one value per term.

The exporters (:mod:`._nlsys`, :mod:`._c`) reproduce the library's time-domain simulator
(:func:`bouc_wen_id.simulate_input`, docs/design.md sections 1 and 9.4): the controllable canonical form
``xsdot = A xs + B v``, ``x = C xs + D v`` of G with ``v(t) = u(t - delay)``, the generalised Bouc-Wen rate
with the terms that change it, and the output terms (on u and, across the hysteretic element, on x:
``rust/simulate/on_x.rs``), with Dahl friction's forces as states on u and on x
(``rust/simulate/with_terms/dahl.rs``). :func:`flatten` checks once what they can export: every term of the
registry :data:`~bouc_wen_id.terms.TERMS` at every place whose parameter has a field of :class:`Flat` (named
by the term's symbol, with ``_<place>`` appended off its usual place), which is every term ``simulate_input``
simulates. The measured-input distortion is refused by name, as the simulator refuses it (it stands for the
harmonics of one measured sine experiment, not a map of an arbitrary input); a term the exporters do not know
(a registry term added without an exporter) is :class:`UnsupportedTermError`.
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
    Term,
    core_terms,
)
from ..validation import check_transfer_function

__all__ = [
    "Flat",
    "EXPORTED",
    "UnsupportedTermError",
    "field_of",
    "flatten",
    "realize",
    "PLAY_ENGAGE_RTOL",
    "PINCHING_CENTRE",
    "PINCHING_WIDTH",
]

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
    #: The series dashpot's ``rho``: the element is driven by ``xpdot - rho w`` at every RK4 stage (0: none,
    #: ``p - 0 w = p`` exactly, so a plant without it rounds as before).
    rho: float = 0.0
    #: The mechanical terms across the hysteretic element, on x (``rust/simulate/on_x.rs``).
    k_x: float = 0.0
    c_x: float = 0.0
    m_x: float = 0.0
    f_x: float = 0.0
    smoothing_x: float = COULOMB_SMOOTHING
    #: Dahl friction on u (level ``fc``, pre-sliding stiffness ``sigma``) and on x (``fc_x``, ``sigma_x``):
    #: its force is one more state at each place (``rust/simulate/with_terms/dahl.rs``); 0: none.
    fc: float = 0.0
    sigma: float = 0.0
    fc_x: float = 0.0
    sigma_x: float = 0.0

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
    def has_on_x(self) -> bool:
        """A term acts on x (then its value needs x's derivatives from the state, on_x.rs)."""
        return self.k_x != 0.0 or self.c_x != 0.0 or self.m_x != 0.0 or self.f_x != 0.0

    @property
    def has_dahl_u(self) -> bool:
        """Dahl friction moves on u (``Fc > 0`` and ``sigma > 0``; either 0 is no friction, dahl.rs)."""
        return self.fc > 0.0 and self.sigma > 0.0

    @property
    def has_dahl_x(self) -> bool:
        """Dahl friction moves on x."""
        return self.fc_x > 0.0 and self.sigma_x > 0.0

    @property
    def has_dahl(self) -> bool:
        """Dahl friction moves at either place: then the output adds ``F_u + F_x`` (the simulator's
        ``dahl_active``; without it the output rounds as before)."""
        return self.has_dahl_u or self.has_dahl_x

    @property
    def w_u(self) -> float:
        """The virgin saturation level ``(alpha / (beta + gamma))^(1/mu)`` (pinching's band scale)."""
        return float((self.alpha / (self.beta + self.gamma)) ** (1.0 / self.mu))


class UnsupportedTermError(InvalidParameterError):
    """A term the exporters cannot write: the input distortion, or a term with no exporter (named)."""


def field_of(cls: type[Term]) -> str:
    """The :class:`Flat` field of term class ``cls``: its symbol at its usual place, ``<symbol>_<place>``
    at another (``ViscousX`` -> ``c_x``)."""
    base = TERMS.get(cls.base_kind, cls)
    return cls.symbol if cls.acts_on == base.acts_on else f"{cls.symbol}_{cls.acts_on.value}"


def _exported() -> tuple[type[Term], ...]:
    fields = set(Flat._fields) - {"a", "crow", "dfeed", "delay", "alpha", "beta", "gamma", "mu", "w0"}
    out = []
    taken: dict[str, type[Term]] = {}
    for cls in TERMS.values():
        f = field_of(cls)
        if cls is Distortion or f not in fields or f in taken:
            continue  # no field, or a second class on one field: not written (refused by name)
        taken[f] = cls
        out.append(cls)
    return tuple(out)


#: The term classes the exporters write, derived from the registry: every class whose parameter has its own
#: field of :class:`Flat` (the distortion excepted): every term at every place the simulator simulates.
EXPORTED: tuple[type[Term], ...] = _exported()


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
        Not a :class:`WienerPlant`.
    UnsupportedTermError
        The measured-input distortion (the simulator's own refusal, word for word), or a term with no
        exporter (a registry term added without one, a class outside the registry).
    """
    if not isinstance(plant, WienerPlant):
        raise InvalidParameterError(f"{what} needs a WienerPlant, got {type(plant).__name__}")
    try:
        core_terms(plant.terms)  # the simulator's own refusals, word for word
    except InvalidParameterError as exc:
        raise UnsupportedTermError(f"{what}: {exc}") from None
    values: dict[str, float] = {}
    for t in plant.terms:
        if type(t) not in EXPORTED:
            raise UnsupportedTermError(
                f"{what}: the term {t.kind!r} ({t.label}) has no exporter; the exporters write "
                f"{', '.join(c.kind for c in EXPORTED)}"
            )
        f = field_of(type(t))
        values[f] = t.value
        if isinstance(t, Coulomb):
            values["smoothing" + f[1:]] = t.smoothing
    num, den, delay = check_transfer_function(plant.linear.num, plant.linear.den, plant.linear.delay)
    a, c, d = realize(num, den)
    h = plant.hysteresis
    return Flat(a, c, d, delay, h.alpha, h.beta, h.gamma, h.mu, h.w0, **values)

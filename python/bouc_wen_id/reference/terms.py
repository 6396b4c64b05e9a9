"""NumPy reference of ``rust/terms.rs``: the terms' vocabulary, written once for the whole oracle.

The oracle spells each term's code name here only, independently of the package's registry
(:mod:`bouc_wen_id.terms`), so that a slip in either shows in the parity tests; :mod:`.augmented` (the
steady-loop model of ``rust/augmented.rs``) and :mod:`.with_terms` (the simulation of
``rust/simulate/with_terms.rs``) take the names from here.
"""

from __future__ import annotations

__all__ = [
    "OFFSET",
    "STIFFNESS",
    "VISCOUS",
    "INERTIA",
    "COULOMB",
    "SENSOR_LAG",
    "ASYMMETRY",
    "PLAY",
    "DEGRADATION",
    "STIFFNESS_DEGRADATION",
    "PINCHING",
    "SERIES_DASHPOT",
    "DAHL",
    "DAHL_SIGMA",
    "PINCHING_CENTRE",
    "PINCHING_WIDTH",
    "PINCHING_MAX",
    "DISTORTION",
    "COULOMB_SMOOTHING_KEY",
    "COULOMB_SMOOTHING",
    "COULOMB_SMOOTHING_MAX",
    "STEADY_TERM_NAMES",
    "SIMULATION_KEYS",
    "PLACE_X",
    "ON_X_TERMS",
    "split_place",
]

OFFSET = "offset"
STIFFNESS = "stiffness"
VISCOUS = "viscous"
INERTIA = "inertia"
COULOMB = "coulomb"
SENSOR_LAG = "sensor_lag"
ASYMMETRY = "asymmetry"
PLAY = "play"
DEGRADATION = "degradation"
STIFFNESS_DEGRADATION = "stiffness_degradation"
PINCHING = "pinching"
#: Spencer's series dashpot: the element driven by its own travel, ``ddot = xdot - rho w``.
SERIES_DASHPOT = "series_dashpot"
#: Dahl friction (``rust/dahl.rs``): its level Fc and its pre-sliding stiffness sigma, given together.
DAHL = "dahl"
DAHL_SIGMA = "dahl_sigma"
#: Pinching's fixed shape, fractions of the saturation level w_u: the band's centre q and width zeta2.
PINCHING_CENTRE = 0.1
PINCHING_WIDTH = 0.2
#: Largest zeta1 the steady-loop fit admits.
PINCHING_MAX = 0.95
DISTORTION = "distortion"
#: The Coulomb term's fixed setting (not a term): the smoothing of its sign, a fraction of the peak velocity.
COULOMB_SMOOTHING_KEY = "coulomb_smoothing"
COULOMB_SMOOTHING = 0.01
COULOMB_SMOOTHING_MAX = 0.5

#: The steady-loop (augmented) model's terms, in the order of the table of design.md 9.1.
STEADY_TERM_NAMES: tuple[str, ...] = (
    OFFSET,
    STIFFNESS,
    VISCOUS,
    INERTIA,
    COULOMB,
    SENSOR_LAG,
    ASYMMETRY,
    PLAY,
    PINCHING,
    DISTORTION,
    SERIES_DASHPOT,
    DAHL,
    DAHL_SIGMA,
)
#: Keys of the simulation's ``terms`` mapping: the code names, plus the Coulomb smoothing.
SIMULATION_KEYS: tuple[str, ...] = (
    OFFSET,
    STIFFNESS,
    VISCOUS,
    INERTIA,
    COULOMB,
    COULOMB_SMOOTHING_KEY,
    SENSOR_LAG,
    ASYMMETRY,
    PLAY,
    DEGRADATION,
    STIFFNESS_DEGRADATION,
    PINCHING,
    SERIES_DASHPOT,
)

#: The tag of the place across the hysteretic element (on its input x): a term there is named
#: ``"<code name>@x"`` (``rust/terms.rs``, ``Place::X``).
PLACE_X = "x"
#: The terms that can act on x: the mechanical ones.
ON_X_TERMS: tuple[str, ...] = (STIFFNESS, VISCOUS, INERTIA, COULOMB, DAHL, DAHL_SIGMA)


def split_place(name: str) -> tuple[str, str]:
    """``(code name, place tag)`` of a term name ``"<code name>[@<tag>]"`` (tag ``""``: its usual place)."""
    base, _, tag = name.partition("@")
    return base, tag

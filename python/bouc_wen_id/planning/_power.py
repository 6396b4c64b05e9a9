"""The non-centrality a term of a given size gives the diagnosis's test of the plain model, per design.

The diagnosis names a term when its one-parameter F-test against the plain model passes (diagnosis/select.py);
the cost drop a true value ``v`` produces on noise-free data is the part of the term's trace the plain model
cannot absorb (diagnosis/limits.py, ``_Profile``): the weighted trace ``r`` (the plain model plus the term at
``v``, minus the plain model) after projecting out the plain model's Jacobian ``J`` (beta, gamma, mu shared;
each experiment's own |G| and phi). With weights ``N_i / sigma^2`` the projection is a sum over experiments:
eliminating experiment i's own (|G_i|, phi_i) leaves the 4 x 4 block ``M_i = [B_i' r_i']^T [B_i' r_i']``
(``B`` the Bouc-Wen columns, primes after removing the own columns), and

    lam = (S_rr - S_rb S_bb^-1 S_br) / sigma^2,   S = sum_i N_i M_i,

the same Schur-complement form as the Cramer-Rao planner's (``_search``): each candidate experiment's block is
computed once, and a design is scored with a 3 x 3 solve. It is linear in the plain model's moves and keeps
the term's own nonlinearity (a sensor lag is a delay in G to first order: what is left grows as tau^2). The
reported non-centrality of a design is then checked by refitting the plain model to the noise-free records
of the plain model plus the term (as ``_Profile.exact``), which the search's first-order projection can
overstate where the plain parameters move far.

The power is that of the term's own test at the targeted step's level (``alpha / 2`` Bonferroni over the
candidates, one-sided for a term confined to ``>= 0``), as diagnosis/limits.py quotes its 50 % and 90 %
limits: ``Phi(sqrt(lam) - z_c)`` (plus ``Phi(-sqrt(lam) - z_c)`` two-sided).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..augmented import AugExperiment, AugParams, augmented_output
from ..diagnosis.candidates import step_candidates
from ..errors import BoucWenIdError, InvalidParameterError, NonFiniteError
from ..model import WienerPlant
from ..terms import STEADY_TERM_NAMES, TERMS, Distortion
from ..validation import real_number

FloatArray = NDArray[np.float64]

#: Terms the diagnosis tests on the averaged period by a one-parameter F-test, and so can be designed for:
#: the distortion term scales the measured input's harmonics, which a planned pure sine does not have; a
#: two-parameter element (Dahl friction: its level and its pre-sliding stiffness, :attr:`Term.companion`,
#: :attr:`Term.part_of`) is fitted as one with two parameters, which a one-size plan does not describe.
DETECTABLE = tuple(
    t for t in STEADY_TERM_NAMES if t != Distortion.kind and not TERMS[t].part_of and not TERMS[t].companion
)
#: The candidates sharing the targeted step's level by default: the diagnosis's own list of what a step
#: tests on pure sines (diagnosis/candidates.py), the one :func:`~bouc_wen_id.diagnose` uses.
DEFAULT_CANDIDATES = len(step_candidates(pure_sines=True))
#: Relative precision of the vague prior on beta, gamma, mu (as ``_search.VAGUE_PRIOR``): keeps a
#: one-experiment design's projection finite.
VAGUE_PRIOR = 1e-8


def check_detect(detect: object) -> tuple[str, float]:
    """``detect``: a mapping of one term code name to its size (the term's parameter, physical units of the
    alpha-normalised model), each checked by name."""
    if not isinstance(detect, dict) or len(detect) != 1:
        raise InvalidParameterError(
            f"detect must be a mapping of one term to its size, e.g. {{'sensor_lag': 1e-3}}; got {detect!r}"
        )
    ((term, size),) = detect.items()
    if isinstance(term, str) and term in TERMS and (TERMS[term].companion or TERMS[term].part_of):
        raise TwoParameterTermError(two_parameter_text(term))
    if term not in DETECTABLE:
        raise InvalidParameterError(
            f"detect: unknown or undetectable term {term!r}; the terms a sine design can be planned to "
            "detect "
            f"are {', '.join(DETECTABLE)}"
        )
    try:
        value = real_number(f"detect[{term!r}]", size)
    except BoucWenIdError as err:  # NaN, infinity, not a number: the user's size, said as such
        raise InvalidParameterError(
            f"detect[{term!r}] = {size!r}: a term's size must be a finite number in the term's units"
        ) from err
    lo, hi = TERMS[term].bounds
    if value == 0.0:
        raise InvalidParameterError(f"detect[{term!r}] = 0: a term of size 0 has nothing to detect")
    plo, phi = TERMS[term].physical
    if not max(lo, plo) <= value <= min(hi, phi):
        what = TERMS[term].unphysical or "a value outside the term's physical range"
        raise UnphysicalSizeError(
            f"detect[{term!r}] = {value:g} is outside the term's physical range [{max(lo, plo):g}, "
            f"{min(hi, phi):g}] ({what}): the diagnosis never names such a value, so no design detects it"
        )
    return term, value


def two_parameter_text(term: str) -> str:
    """Why a two-parameter element (Dahl friction) cannot be planned for one size; what to plan instead."""
    element = TERMS[term].part_of or term
    # the same place's limits (a Dahl element on x: its limits on x), ``Term.limits``: spring, then sliding
    spring, sliding = (*getattr(TERMS[element], "limits", ()), "its spring limit", "its sliding limit")[:2]
    cls, sym = TERMS[element], TERMS[element].symbol
    return (
        f"detect: {term!r} is a parameter of {element!r} ({cls.label}), a two-parameter element (its level "
        f"{sym} and {cls.companion!r}) that the diagnosis fits and tests together (an F-test of 2 degrees of "
        f"freedom). One size cannot describe it: its trace, and so the power, depend on the ratio sigma A / "
        f"{sym} (A the travel amplitude) as much as on the level, and at the null (level 0) the companion's "
        "Jacobian column is zero, so the planner's first-order projection of a one-parameter term does not "
        f"exist. Plan for the limit you expect instead: {sliding!r} = the level (sliding: sigma A / Fc >> "
        f"1) or {spring!r} = sigma (a spring: sigma A / Fc << 1); the diagnosis tests those too. "
        f"Plannable terms: {', '.join(DETECTABLE)}"
    )


class TwoParameterTermError(InvalidParameterError):
    """A parameter of a two-parameter element (Dahl friction) given to a one-size plan (``check_detect``)."""


class OversizedTermError(InvalidParameterError):
    """A size whose term would dwarf the plant's own output at every frequency of the band, overflow the
    model's output or make it unsolvable (:func:`check_scale`)."""


#: Largest ratio of a planned term's change of the output (its largest magnitude) to the plain model's own
#: output swing (peak to peak), at the largest amplitude the plan may use, that a plan accepts at *some*
#: frequency of the band (the term is refused only where it exceeds this at every frequency): beyond it the
#: prior is not the plant (the term would be the plant), and its output overflows at sizes such as 1e308.
MAX_TERM_RATIO = 100.0
#: Frequencies, log-spaced over the band, at which :func:`check_scale` compares the term with the plant when
#: not given the planner's own grid.
SCALE_POINTS = 12


def _term_output(e: AugExperiment, par: AugParams, substeps: int) -> tuple[Optional[FloatArray], str]:
    """One steady period of the model with the term: ``(y, "")``, or ``(None, why)`` where its output is not
    finite (``"overflow"``) or its solve fails (the error's text)."""
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            y = np.asarray(augmented_output(e, par, 0, substeps=substeps), dtype=np.float64)
    except (NonFiniteError, FloatingPointError, OverflowError):
        return None, "overflow"
    except BoucWenIdError as err:
        text = str(err)
        return None, f"{type(err).__name__}: {text if len(text) <= 160 else text[:157] + '...'}"
    return (y, "") if np.all(np.isfinite(y)) else (None, "overflow")


def check_scale(
    prior: WienerPlant,
    term: str,
    size: float,
    band: Sequence[float],
    amplitude: ArrayLike,
    *,
    omegas: Optional[ArrayLike] = None,
    samples: ArrayLike = 512,
    substeps: int = 8,
) -> float:
    """The smallest ratio, over the band, of the term's change of the output (its largest magnitude: an
    offset counts) to the plain model's own output swing (peak to peak), at ``amplitude`` (one, or one per
    frequency: the largest the plan may use there); at ``omegas`` (default :data:`SCALE_POINTS` log-spaced
    over ``band``) with ``samples`` per period and ``substeps``, the planner's resolution.

    The term is judged against the plant where it would be measured: it is refused
    (:class:`OversizedTermError`) only where it exceeds :data:`MAX_TERM_RATIO` times the plant's swing at
    every frequency, or where the model with it overflows (a non-finite output) or cannot be solved. The
    prior's own errors (an invalid parameter, a solve that fails without the term) are raised as they are."""
    lo, hi = float(band[0]), float(band[-1])
    om = np.geomspace(lo, hi, SCALE_POINTS) if omegas is None else np.asarray(omegas, dtype=np.float64)
    amps = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), om.shape)
    sam = np.broadcast_to(np.asarray(samples, dtype=np.int64), om.shape)
    ratios = []
    for omega, amp, n in zip(om, amps, sam):
        e = AugExperiment(np.zeros(int(n)), float(amp), float(omega), 0.0, 1.0)
        par = aug_params(prior, [float(omega)])
        y0 = np.asarray(augmented_output(e, par, 0, substeps=substeps), dtype=np.float64)  # the prior's own
        y1, why = _term_output(e, par.with_term(term, size), substeps)
        if y1 is None:
            _refuse(term, size, (lo, hi), float(amp), f"{why} at {omega:.4g} rad/s")
        assert y1 is not None
        ratios.append(float(np.max(np.abs(y1 - y0))) / max(float(np.ptp(y0)), 1e-300))
    least = min(ratios)
    if not least <= MAX_TERM_RATIO:
        where = float(om[int(np.argmin(ratios))])
        _refuse(term, size, (lo, hi), float(np.max(amps)), f"{least:.3g}x at best ({where:.4g} rad/s)")
    return least


def _refuse(term: str, size: float, band: tuple[float, float], amplitude: float, what: str) -> None:
    """:class:`OversizedTermError`: ``what`` is the ratio, ``overflow`` or a failed solve of the model with
    the term."""
    if what.startswith("overflow"):
        said = f"overflow the model's output (beyond floating point{what[len('overflow') :]})"
    elif "x at best" in what:
        said = (
            f"change the output by more than {MAX_TERM_RATIO:g}x the plain model's own output swing (peak to "
            f"peak) at every frequency of the band: {what}"
        )
    else:
        said = f"make the model unsolvable ({what})"
    raise OversizedTermError(
        f"detect[{term!r}] = {size:g}: at amplitudes up to {amplitude:g} across the band ({band[0]:g}-"
        f"{band[1]:g} rad/s) the term would {said}; a plan is for a term missing from a model that "
        f"otherwise fits. Check the size's units ({TERMS[term].unit or '-'} in the alpha-normalised model) "
        "or the prior plant"
    )


class UnphysicalSizeError(InvalidParameterError):
    """A size outside the term's physical range (:attr:`Term.physical`), which the diagnosis never names."""


def physical_side(term: str) -> bool:
    """Whether the term's physical range is one-sided (``>= 0``): only values of that sign are named (the
    diagnosis refuses the others, diagnosis/select.py ``_admissible``), so the power counts one tail."""
    lo, hi = TERMS[term].physical
    return math.isfinite(lo) != math.isfinite(hi)


def critical(term: str, alpha: float, candidates: int) -> tuple[float, float, bool]:
    """``(z_c, level, one_sided)`` of the term's test at the targeted step (module docstring): one-sided
    (its p halved) for a term whose fitted range is confined to ``>= 0``, two-sided otherwise."""
    level = 0.5 * alpha / candidates
    return z_critical(term, level), level, TERMS[term].bounds[0] == 0.0


def z_critical(term: str, level: float) -> float:
    """The normal critical value of ``term``'s own test at ``level`` (per candidate): one-sided for a term
    whose fitted range is ``>= 0`` (diagnosis/select.py ``BOUNDARY_TERMS``), two-sided otherwise."""
    from scipy.special import ndtri  # type: ignore[import-untyped]

    one = TERMS[term].bounds[0] == 0.0
    return float(ndtri(1.0 - (level if one else 0.5 * level)))


def power_at(lam: float, z_c: float, one_sided: bool) -> float:
    """Power of the term's test at non-centrality ``lam`` (normal approximation of the F-test)."""
    from scipy.special import ndtr

    if not math.isfinite(lam):
        return math.nan
    d = math.sqrt(max(lam, 0.0))
    return float(ndtr(d - z_c)) + (0.0 if one_sided else float(ndtr(-d - z_c)))


def lam_needed(power: float, z_c: float) -> float:
    """The non-centrality at which the (one-sided) test reaches ``power``."""
    from scipy.special import ndtri

    return float((z_c + ndtri(power)) ** 2)


def aug_params(prior: WienerPlant, omegas: Sequence[float]) -> AugParams:
    """The prior as the augmented model's parameters at ``omegas`` (grid phase 0: ``phi_i`` is G's lag)."""
    norm = prior.normalized()
    h = norm.hysteresis
    gains, phases = norm.linear.gain_phase(list(omegas))
    return AugParams(h.beta, h.gamma, h.mu, (), np.zeros(0), np.asarray(gains), np.asarray(phases))


def experiment_block(
    prior: WienerPlant,
    omega: float,
    amplitude: float,
    samples: int,
    term: str,
    size: float,
    substeps: int,
    rivals: Sequence[str] = (),
) -> FloatArray:
    """``M`` (4 x 4, at unit weight: one averaged period, noise sd 1) of one sine experiment; with
    ``rivals`` (terms linear in their value, :attr:`Term.linear`) one more row and column each: the rival's
    trace per unit value."""
    e = AugExperiment(np.zeros(samples), amplitude, omega, 0.0, 1.0)
    par = aug_params(prior, [omega])
    out = augmented_output(e, par, 0, substeps=substeps, jacobian=True)
    y0 = np.asarray(out.y)
    r = np.asarray(augmented_output(e, par.with_term(term, size), 0, substeps=substeps)) - y0
    more = [
        (np.asarray(augmented_output(e, par.with_term(t, RIVAL_STEP), 0, substeps=substeps)) - y0)
        / RIVAL_STEP
        for t in rivals
    ]
    own = np.asarray(out.own_jacobian)
    u, sv, _ = np.linalg.svd(own, full_matrices=False)
    q = u[:, sv > 1e-10 * max(float(sv[0]), 1e-300)]
    cols = np.column_stack([np.asarray(out.jacobian)[:, :3], r, *more])
    cols = cols - q @ (q.T @ cols)
    block: FloatArray = cols.T @ cols
    return block


#: The value at which a rival's trace is taken (it is linear in its value: the trace per unit value).
RIVAL_STEP = 1e-3


def lam_of(blocks: FloatArray, periods: FloatArray, scale: FloatArray, noise_sd: float) -> float:
    """The linearised non-centrality of experiments with 4 x 4 ``blocks`` (k, 4, 4) and ``periods`` N."""
    s = np.einsum("i,ijk->jk", periods, blocks[:, :4, :4])
    sbb = s[:3, :3] + VAGUE_PRIOR * np.diag(1.0 / scale**2)
    try:
        absorbed = float(s[3, :3] @ np.linalg.solve(sbb, s[:3, 3]))
    except np.linalg.LinAlgError:
        return math.nan
    return max(float(s[3, 3]) - absorbed, 0.0) / noise_sd**2


def refitted_lam(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    noise_sd: float,
    substeps: int,
) -> float:
    """The non-centrality after refitting the plain model to the noise-free records of the prior plus the term
    (``design``: :class:`~._result.PlannedExperiment` s); NaN when the fit fails."""
    from ..diagnosis.fitting import fit_from

    par = aug_params(prior, [e.frequency for e in design])
    exps = [
        AugExperiment(np.zeros(e.samples_per_period), e.amplitude, e.frequency, 0.0, e.periods / noise_sd**2)
        for e in design
    ]
    truth = par.with_term(term, size)
    try:
        ys = [np.asarray(augmented_output(e, truth, i, substeps=substeps)) for i, e in enumerate(exps)]
        fit = fit_from([replace(e, ybar=y) for e, y in zip(exps, ys)], par, substeps)
    except (BoucWenIdError, FloatingPointError):
        return math.nan
    return float(fit.cost) if fit is not None else math.nan


@dataclass(frozen=True)
class DetectionPower:
    """What a design predicts for the diagnosis's test of one term at one size."""

    term: str
    size: float
    #: The first-order non-centrality (the search's), and the one after refitting the plain model (NaN: the
    #: refit failed; the power then uses the first-order value).
    lam_linear: float
    lam: float
    #: The test's level (per candidate), whether one-sided, and its normal critical value.
    level: float
    one_sided: bool
    z_c: float
    power: float
    total_time: float

    @property
    def lam_used(self) -> float:
        return self.lam if math.isfinite(self.lam) else self.lam_linear

    def periods_factor(self, power: float = 0.9) -> float:
        """Factor on every experiment's periods that brings the power to ``power`` (lam grows as N)."""
        lam = self.lam_used
        return lam_needed(power, self.z_c) / lam if lam > 0 else math.inf

    def to_dict(self) -> dict[str, Any]:
        def n(v: float) -> Optional[float]:
            return v if math.isfinite(v) else None

        return {
            "term": self.term,
            "size": self.size,
            "lam_linear": n(self.lam_linear),
            "lam": n(self.lam),
            "level": self.level,
            "one_sided": self.one_sided,
            "power": n(self.power),
            "total_time": self.total_time,
            "periods_factor_90": n(self.periods_factor(0.9)),
        }


def detection_power(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    *,
    noise_sd: float,
    alpha: float = 0.05,
    candidates: int = DEFAULT_CANDIDATES,
    substeps: int = 8,
    refit: bool = True,
) -> DetectionPower:
    """The predicted power of the diagnosis's test of ``term`` at ``size`` on ``design`` (experiments with
    ``frequency, amplitude, periods, samples_per_period`` and ``duration``, e.g. ``PlannedExperiment`` s)
    for a plant ``prior`` with white output noise ``noise_sd`` per sample (module docstring)."""
    term, size = check_detect({term: size})
    if not design:
        raise InvalidParameterError("design has no experiments")
    h = prior.normalized().hysteresis
    scale = np.where(np.array([h.beta, h.gamma, h.mu]) != 0, np.abs([h.beta, h.gamma, h.mu]), 1.0)
    blocks = np.array(
        [
            experiment_block(prior, e.frequency, e.amplitude, e.samples_per_period, term, size, substeps)
            for e in design
        ]
    )
    periods = np.array([float(e.periods) for e in design])
    lam1 = lam_of(blocks, periods, scale, noise_sd)
    lam = refitted_lam(prior, design, term, size, noise_sd, substeps) if refit else math.nan
    z_c, level, one = critical(term, alpha, candidates)
    used = lam if math.isfinite(lam) else lam1
    total = float(sum(e.duration for e in design))
    tails_one = one or physical_side(term)  # a negative damping is never named: its tail is no detection
    return DetectionPower(term, size, lam1, lam, level, one, z_c, power_at(used, z_c, tails_one), total)


__all__ = [
    "DETECTABLE",
    "DEFAULT_CANDIDATES",
    "DetectionPower",
    "UnphysicalSizeError",
    "TwoParameterTermError",
    "OversizedTermError",
    "MAX_TERM_RATIO",
    "check_scale",
    "detection_power",
    "check_detect",
]

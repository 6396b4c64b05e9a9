"""Physical terms (design.md 9.1) as plant parts, and the time-domain simulation with them (9.4).

Value types (validation with named errors, dict/JSON round trips, alpha normalisation), Rust vs NumPy
reference parity per term, closed-form checks of every term, and that a plant without terms still takes
the plain path bit for bit.
"""

from __future__ import annotations

import hashlib
import json
import math
import pickle
from dataclasses import FrozenInstanceError
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id import io as bio
from bouc_wen_id.errors import InvalidParameterError, NonFiniteError
from bouc_wen_id.model import BoucWen, SinePlan, TransferFunction, WienerPlant
from bouc_wen_id.terms import (
    DIAGNOSIS_CANDIDATES,
    STEADY_TERM_NAMES,
    TERM_NAMES,
    TERMS,
    Asymmetry,
    Coulomb,
    Inertia,
    Offset,
    Place,
    Play,
    SensorLag,
    StartContext,
    Stiffness,
    Term,
    Viscous,
    ViscousX,
    core_terms,
    parse_terms,
    term_from_dict,
)
from numpy.testing import assert_allclose, assert_array_equal
from scipy import signal  # type: ignore[import-untyped]

TWO_PI = 2.0 * math.pi

ONE_OF_EACH: tuple[Term, ...] = (
    Offset(0.3),
    Stiffness(0.4),
    Viscous(0.05),
    Inertia(0.01),
    Coulomb(0.2, smoothing=0.02),
    SensorLag(0.04),
    Asymmetry(0.3),
    Play(0.1),
)


def _scale(a: np.ndarray) -> float:
    return float(np.max(np.abs(a)))


def _plant(terms: tuple[Term, ...] = (), alpha: float = 1.0) -> WienerPlant:
    return WienerPlant(
        TransferFunction([1.0, 2.0], [0.1, 0.7, 2.0], 0.03),
        BoucWen(beta=0.9 * alpha, gamma=0.3 * alpha, mu=1.6, alpha=alpha),
        terms,
    )


# --------------------------------------------------------------------------------------------------
# Value types
# --------------------------------------------------------------------------------------------------


#: The terms at their usual place (a term at another place is a sibling class, ``"<kind>@<place>"``).
USUAL = {k: c for k, c in TERMS.items() if c.base_kind == k}
#: The mechanical terms, which also act across the hysteretic element (on x): tests/test_place.py.
ON_X = {k: c for k, c in TERMS.items() if c.base_kind != k}


def test_registry_follows_the_design_table() -> None:
    assert [c.base_kind for c in ON_X.values()] == [
        "stiffness",
        "viscous",
        "inertia",
        "coulomb",
        "dahl",
        "dahl_sigma",
    ]
    assert all(c.acts_on == Place.X and k == f"{c.base_kind}@x" for k, c in ON_X.items())
    assert list(USUAL) == [
        "offset",
        "stiffness",
        "viscous",
        "inertia",
        "coulomb",
        "sensor_lag",
        "asymmetry",
        "play",
        "degradation",
        "stiffness_degradation",
        "pinching",
        "distortion",
        "series_dashpot",
        "dahl",
        "dahl_sigma",
    ]
    units = {kind: cls.units(y="N", u="mm") for kind, cls in USUAL.items()}
    assert units == {
        "offset": "N",
        "stiffness": "N/mm",
        "viscous": "N s/mm",
        "inertia": "N s^2/mm",
        "coulomb": "N",
        "sensor_lag": "s",
        "asymmetry": "1/N^mu",
        "play": "N",
        "degradation": "1/N^2",
        "stiffness_degradation": "1/N^2",
        "pinching": "",
        "distortion": "",
        "series_dashpot": "1/s",
        "dahl": "N",
        "dahl_sigma": "N/mm",
    }
    for kind, cls in USUAL.items():
        assert cls.kind == kind
        assert cls.description and cls.signature and cls.symbol
        assert cls.rust_kind == kind and cls.label and cls.places[0] == cls.acts_on
        hysteresis = (
            "asymmetry",
            "play",
            "degradation",
            "stiffness_degradation",
            "pinching",
            "distortion",
            "series_dashpot",
        )
        on_u = ("stiffness", "viscous", "inertia", "coulomb", "dahl", "dahl_sigma")
        assert cls.acts_on == (
            Place.HYSTERESIS if kind in hysteresis else Place.INPUT if kind in on_u else Place.OUTPUT
        )
        assert cls.acts_on.label
    assert TERM_NAMES == tuple(TERMS)
    drift_only = ("degradation", "stiffness_degradation")
    assert STEADY_TERM_NAMES == tuple(k for k in TERMS if k not in drift_only)
    # A two-term element's second term (Dahl friction's sigma) is added with its first, not on its own.
    seconds = ("dahl_sigma", "dahl_sigma@x")
    assert DIAGNOSIS_CANDIDATES == (*(k for k in STEADY_TERM_NAMES if k not in seconds), *drift_only)
    # The lower bounds of the value types, and the physical ranges the diagnosis will name within.
    assert {k for k, c in USUAL.items() if c.bounds[0] == 0.0} == {
        "sensor_lag",
        "play",
        "pinching",
        "series_dashpot",
        "dahl",
        "dahl_sigma",
        *drift_only,
    }
    assert {k for k, c in USUAL.items() if c.physical[0] == 0.0} == {
        "stiffness",
        "distortion",
        "viscous",
        "inertia",
        "coulomb",
        "sensor_lag",
        "play",
        "pinching",
        "series_dashpot",
        "dahl",
        "dahl_sigma",
        *drift_only,
    }
    assert [k for k, c in USUAL.items() if c.linear] == [
        "offset",
        "stiffness",
        "viscous",
        "inertia",
        "coulomb",
    ]
    for t in ONE_OF_EACH:
        assert t.value == getattr(t, t.symbol)
        assert t.with_value(0.07).value == 0.07
        with pytest.raises(FrozenInstanceError):
            setattr(t, t.symbol, 1.0)


def test_scale_factors_follow_the_units() -> None:
    # A parameter in [y]^a [u]^b (asymmetry: [y]^-mu) scales by y^a u^b with the data (design.md 10.1).
    y, u, mu = 8.0, 0.5, 1.5
    got = {k: c.scale_factor(y, u, mu) for k, c in USUAL.items()}
    # On x (in units of y): k, c, m are [y]/[y] times s^n, the friction [y] (Dahl's: Fc [y], sigma [y]/[y]).
    assert [c.scale_factor(y, u, mu) for c in ON_X.values()] == [1.0, 1.0, 1.0, y, y, 1.0]
    assert got == {
        "offset": y,
        "stiffness": y / u,
        "viscous": y / u,
        "inertia": y / u,
        "coulomb": y,
        "sensor_lag": 1.0,
        "asymmetry": y**-mu,
        "play": y,
        "degradation": y**-2,
        "stiffness_degradation": y**-2,
        "pinching": 1.0,
        "distortion": 1.0,
        "series_dashpot": 1.0,
        "dahl": y,
        "dahl_sigma": y / u,
    }


def test_start_guesses_come_from_the_terms() -> None:
    calls: list[int] = []

    def projection() -> float:
        calls.append(1)
        return 0.25

    ctx = StartContext(
        latent_amplitudes=(2.0, 0.5), max_frequency=4.0, beta=0.6, gamma=0.2, projection=projection
    )
    assert SensorLag.start(ctx) == (0.01 / 4.0, 0.1 / 4.0)
    assert Play.start(ctx) == (0.005, 0.05, 0.15)
    assert Asymmetry.start(ctx) == pytest.approx((0.0, 0.24, -0.24))
    assert TERMS["distortion"].start(ctx) == (1.0, 0.0)
    assert calls == []  # only the linear terms project the residual
    assert Viscous.start(ctx) == (0.25, 0.0) and calls == [1]


def test_parse_terms_names_the_vocabulary() -> None:
    assert parse_terms(["play", "offset"]) == ("play", "offset")
    with pytest.raises(InvalidParameterError, match="unknown term 'spring'"):
        parse_terms(["spring"])
    with pytest.raises(InvalidParameterError, match="given twice"):
        parse_terms(["play", "play"])
    with pytest.raises(InvalidParameterError, match="not the string"):
        parse_terms("play")
    with pytest.raises(InvalidParameterError, match="unknown term 'degradation'"):
        parse_terms(["degradation"], STEADY_TERM_NAMES)


#: Literals that spell a code name in another sense, in files owned elsewhere (see the test below).
NOT_A_TERM = {
    ("offset", "result.py"): "the identification's averaged-output DC, a JSON field of IdentificationResult",
    ("play", "reference/path_loop.py"): "the path loop's argument, named in its finiteness error",
}


def _literal_files(name: str) -> list[str]:
    """The package's Python files holding the string literal ``name`` (docstrings and f-strings aside)."""
    import ast

    root = Path(bw.__file__).parent
    out = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if any(isinstance(n, ast.Constant) and n.value == name for n in ast.walk(tree)):
            rel = path.relative_to(root).as_posix()
            if (name, rel) not in NOT_A_TERM:
                out.append(rel)
    return out


#: The Rust crate (the tests run from the source tree, beside it).
RUST = Path(__file__).resolve().parents[1] / "rust"
#: Rust literals that spell a code name in another sense.
NOT_A_RUST_TERM = {("play", "path_loop.rs"): "the path loop's argument, named in its finiteness error"}


def _rust_literal_files(name: str) -> list[str]:
    """The crate's files holding ``"name"`` outside comments."""
    out = []
    for path in sorted(RUST.rglob("*.rs")):
        code = [line.split("//")[0] for line in path.read_text(encoding="utf-8").splitlines()]
        rel = path.relative_to(RUST).as_posix()
        if any(f'"{name}"' in line for line in code) and (name, rel) not in NOT_A_RUST_TERM:
            out.append(f"rust/{rel}")
    return out


#: The registry's modules that hold term classes (``terms/__init__.py`` is the registry's list: classes only).
REGISTRY_MODULES = ("terms/_on_output.py", "terms/_mechanical.py", "terms/_hysteretic.py")


def test_the_code_name_scan_reads_every_registry_module() -> None:
    # The rule below is only as good as its scan: every module of the registry package is read, and each
    # module that holds terms spells some code name (a new module of terms is scanned without a change here).
    root = Path(bw.__file__).parent
    modules = sorted(p.relative_to(root).as_posix() for p in (root / "terms").glob("*.py"))
    assert modules == sorted(("terms/__init__.py", "terms/_base.py", *REGISTRY_MODULES))
    seen = {f for name in USUAL for f in _literal_files(name)}
    assert set(REGISTRY_MODULES) <= seen and not seen & {"terms/__init__.py", "terms/_base.py"}


#: Where each registry module's terms act (docs/design.md 9.1: a new term is a class in its place's module).
MODULE_PLACES = {
    "terms/_on_output.py": {Place.OUTPUT},
    "terms/_mechanical.py": {Place.INPUT, Place.X},
    "terms/_hysteretic.py": {Place.HYSTERESIS},
}


def test_each_term_class_is_defined_once_in_the_module_of_its_place() -> None:
    import ast

    root = Path(bw.__file__).parent
    assert set(MODULE_PLACES) == set(REGISTRY_MODULES)
    defined: dict[str, list[str]] = {}
    for rel in (p.relative_to(root).as_posix() for p in (root / "terms").glob("*.py")):
        tree = ast.parse((root / rel).read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, ast.ClassDef):
                defined.setdefault(node.name, []).append(rel)
    for cls in TERMS.values():
        homes = defined.get(cls.__name__, [])
        assert len(homes) == 1 and homes[0] in MODULE_PLACES, (cls.__name__, homes)
        assert cls.acts_on in MODULE_PLACES[homes[0]], (cls.__name__, homes[0], cls.acts_on)
    # The protocol module holds the protocol only: no term class.
    assert {name for name, homes in defined.items() if "terms/_base.py" in homes} == {
        "Place",
        "StartContext",
        "Term",
    }


@pytest.mark.parametrize("name", list(USUAL))
def test_a_code_name_is_spelled_in_at_most_three_files(name: str) -> None:
    """Issue 17: a term's code name is written as a string in three files only: its class's module in the
    registry (``terms/_mechanical.py`` for ``viscous``), the Rust enum (``rust/terms.rs``, ``TermKind``) and
    the oracle's vocabulary (``reference/terms.py``); everything else, the registry's list
    (``terms/__init__.py``) included, uses the class (``SensorLag.kind``) or the registry."""
    assert RUST.is_dir(), f"{RUST}: the tests run from the source tree, beside the crate"
    files = _literal_files(name) + _rust_literal_files(name)
    registry = [f for f in files if f.startswith("terms/")]
    assert len(registry) == 1 and registry[0] in REGISTRY_MODULES, files
    source = (Path(bw.__file__).parent / registry[0]).read_text(encoding="utf-8")
    assert f"class {USUAL[name].__name__}(" in source, f"{name} is spelled away from its class"
    assert sorted(set(files) - set(registry)) == ["reference/terms.py", "rust/terms.rs"], files


@pytest.mark.parametrize(
    ("make", "error", "text"),
    [
        (lambda: Offset(float("nan")), NonFiniteError, "offset.y0"),
        (lambda: Viscous(float("inf")), NonFiniteError, "viscous.c"),
        (lambda: Stiffness("1"), InvalidParameterError, "real number"),  # type: ignore[arg-type]
        (lambda: Inertia(1j), InvalidParameterError, "real number"),  # type: ignore[arg-type]
        (lambda: SensorLag(-1e-3), InvalidParameterError, "tau"),
        (lambda: Play(-0.1), InvalidParameterError, "half-width"),
        (lambda: Coulomb(1.0, smoothing=0.0), InvalidParameterError, "smoothing"),
        (lambda: Coulomb(1.0, smoothing=0.6), InvalidParameterError, "smoothing"),
        (lambda: Coulomb(1.0, smoothing=float("nan")), NonFiniteError, "smoothing"),
    ],
)
def test_terms_validate_with_named_errors(make: Any, error: type[Exception], text: str) -> None:
    with pytest.raises(error, match=text):
        make()


def test_admissible_edges_are_accepted() -> None:
    assert Coulomb(-1.0, smoothing=0.5).smoothing == 0.5
    assert SensorLag(0.0).tau == 0.0 and Play(0.0).b == 0.0
    assert Offset(np.float32(2.5)).y0 == 2.5 and isinstance(Offset(np.float32(2.5)).y0, float)


def test_term_dicts_round_trip() -> None:
    for t in ONE_OF_EACH:
        d = t.to_dict()
        assert d["kind"] == t.kind
        back = term_from_dict(json.loads(json.dumps(d)))
        assert back == t and type(back) is type(t)
    assert Coulomb(0.5).to_dict() == {"kind": "coulomb", "f": 0.5, "smoothing": 0.01}
    with pytest.raises(InvalidParameterError, match="unknown term kind 'spring'"):
        term_from_dict({"kind": "spring", "k": 1.0})
    with pytest.raises(InvalidParameterError, match="'c' is missing"):
        term_from_dict({"kind": "viscous"})
    with pytest.raises(InvalidParameterError, match="unknown field"):
        term_from_dict({"kind": "viscous", "c": 1.0, "d": 2.0})
    with pytest.raises(InvalidParameterError, match="needs kind 'play'"):
        Play.from_dict({"kind": "offset", "b": 1.0})
    with pytest.raises(InvalidParameterError, match="mapping"):
        term_from_dict([("kind", "play")])  # type: ignore[arg-type]
    assert core_terms(ONE_OF_EACH) == {
        "offset": 0.3,
        "stiffness": 0.4,
        "viscous": 0.05,
        "inertia": 0.01,
        "coulomb": 0.2,
        "coulomb_smoothing": 0.02,
        "sensor_lag": 0.04,
        "asymmetry": 0.3,
        "play": 0.1,
    }


#: A ``ViscousX(1.0)`` pickled (protocol 0) by the single-file registry of main a301eb6, before the split.
OLD_PICKLE = (
    b"ccopy_reg\n_reconstructor\np0\n(cbouc_wen_id.terms\nViscousX\np1\nc__builtin__\nobject\np2\nNtp3\n"
    b"Rp4\n(dp5\nVc\np6\nF1.0\nsb."
)


def test_pickles_name_the_one_public_module() -> None:
    # The classes live in the registry's private modules but are published as bouc_wen_id.terms.<Name>: a
    # pickle written before the split loads, and one written now names the same path (old code loads it).
    assert pickle.loads(OLD_PICKLE) == ViscousX(1.0)
    assert pickle.dumps(ViscousX(1.0), protocol=0) == OLD_PICKLE
    for cls in (*TERMS.values(), Place, Term, StartContext):
        assert cls.__module__ == "bouc_wen_id.terms", cls
    for cls in TERMS.values():  # every term, at every place
        t = cls(**{cls.symbol: 0.25})
        back = pickle.loads(pickle.dumps(t))
        assert back == t and type(back) is cls
        assert b"cbouc_wen_id.terms\n" + cls.__name__.encode() + b"\n" in pickle.dumps(t, protocol=0)
    assert pickle.loads(pickle.dumps(Place.X)) is Place.X


def test_plant_validates_its_terms() -> None:
    with pytest.raises(InvalidParameterError, match="'viscous' is given twice"):
        _plant((Viscous(0.1), Offset(1.0), Viscous(0.2)))
    # beta + gamma = 1.2: |delta| must stay below it.
    assert _plant((Asymmetry(-1.19),)).terms == (Asymmetry(-1.19),)
    with pytest.raises(InvalidParameterError, match="beta \\+ gamma"):
        _plant((Asymmetry(1.2),))
    with pytest.raises(InvalidParameterError, match="bouc_wen_id.terms objects"):
        _plant(({"kind": "offset", "y0": 1.0},))  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="wrap a single one"):
        _plant(Offset(1.0))  # type: ignore[arg-type]
    # Any sequence is stored as a tuple, in the order given; the plain constructor still works.
    p = _plant([Play(0.1), Offset(1.0)])  # type: ignore[arg-type]
    assert p.terms == (Play(0.1), Offset(1.0))
    assert p.term("offset") == Offset(1.0) and p.term("viscous") is None
    assert WienerPlant(p.linear, p.hysteresis).terms == ()


def test_plant_dicts_round_trip_and_old_dicts_load(tmp_path: Path) -> None:
    plant = _plant(ONE_OF_EACH)
    back = WienerPlant.from_dict(json.loads(json.dumps(plant.to_dict())))
    assert back.terms == plant.terms
    assert back.hysteresis == plant.hysteresis
    assert_array_equal(back.linear.den, plant.linear.den)
    # A plain plant's dict is what it was before terms existed, and such a dict still loads.
    plain = _plant()
    old = plain.to_dict()
    assert set(old) == {"linear", "hysteresis"}
    assert WienerPlant.from_dict(old).terms == ()
    with pytest.raises(InvalidParameterError, match="unknown term kind"):
        WienerPlant.from_dict({**old, "terms": [{"kind": "magic", "x": 1.0}]})
    # The recording files carry the plant with its terms.
    plan = SinePlan([2.0], 1.0, settle_periods=0, periods=1, samples_per_period=32, substeps=1)
    (rec,) = bw.simulate(plant, plan)
    assert rec.plant is plant
    bio.write_csv(tmp_path / "rec.csv", rec)
    loaded = bio.read_csv(tmp_path / "rec.csv")
    assert isinstance(loaded, bw.Recording) and loaded.plant is not None
    assert loaded.plant.terms == plant.terms


def test_cramer_rao_refuses_a_plant_with_terms() -> None:
    plan = SinePlan([2.0], 1.0, noise_sd=0.01)
    with pytest.raises(InvalidParameterError, match="plain Wiener-Bouc-Wen model.*viscous, play"):
        bw.cramer_rao(_plant((Viscous(0.1), Play(0.1))), plan)
    assert bw.cramer_rao(_plant(), plan).beta > 0


def test_normalized_maps_the_terms_and_keeps_the_output() -> None:
    alpha = 2.5
    plant = _plant(ONE_OF_EACH, alpha=alpha)
    norm = plant.normalized()
    assert norm.hysteresis.alpha == 1.0
    expected = {t.kind: t.value for t in ONE_OF_EACH}
    expected["asymmetry"] = 0.3 / alpha
    expected["play"] = 0.1 * alpha
    assert {t.kind: t.value for t in norm.terms} == pytest.approx(expected, rel=1e-15)
    assert norm.term("coulomb") == Coulomb(0.2, smoothing=0.02)
    plan = SinePlan([1.5, 6.0], [1.2, 0.7], settle_periods=1, periods=2, samples_per_period=64)
    for a, b in zip(bw.simulate(plant, plan), bw.simulate(norm, plan)):
        assert a.x is not None and b.x is not None
        # x scales by alpha, the output does not change: the two plants are the same system.  Only
        # rounding differs (alpha = 2.5 is not a power of two): 1e-11 of the peak leaves a wide margin.
        assert_allclose(b.x, alpha * a.x, atol=1e-11 * _scale(b.x))
        assert_allclose(b.y, a.y, atol=1e-11 * _scale(a.y))
        assert a.w is not None
        assert _scale(a.y - a.w) > 0.1  # the terms matter here


# --------------------------------------------------------------------------------------------------
# Rust vs the NumPy reference
# --------------------------------------------------------------------------------------------------

SINGLE_TERMS = [
    {"offset": 0.7},
    {"stiffness": -0.6},
    {"viscous": 0.2},
    {"inertia": 0.05},
    {"coulomb": 0.4, "coulomb_smoothing": 0.03},
    {"sensor_lag": 0.07},
    {"asymmetry": 0.35},
    {"play": 0.15},
    {"sensor_lag": 0.02, "play": 0.1, "asymmetry": -0.3, "coulomb": 0.3, "inertia": 0.02, "viscous": 0.1},
]


def _random_case(helpers: Any, order: int, seed: int) -> tuple[tuple[Any, ...], float, float, float]:
    rng = np.random.default_rng([707, order, seed])
    num, den, delay = helpers.random_tf(rng, order)
    alpha, beta, gamma, mu, w0 = helpers.random_bouc_wen(rng)
    omega = float(rng.uniform(0.5, 6.0))
    dt = TWO_PI / omega / int(rng.integers(24, 64))
    amp = float(rng.uniform(0.5, 2.5) * rng.choice([-1.0, 1.0]))
    return (num, den, delay, alpha, beta, gamma, mu, w0), amp, omega, dt


@pytest.mark.parametrize("terms", SINGLE_TERMS, ids=lambda t: "+".join(t))
@pytest.mark.parametrize("order", [0, 1, 3])
@pytest.mark.parametrize("seed", [0, 1])
def test_rust_matches_reference_per_term(
    helpers: Any, terms: dict[str, float], order: int, seed: int
) -> None:
    args, amp, omega, dt = _random_case(helpers, order, seed)
    beta, gamma = args[4], args[5]
    terms = dict(terms)
    if "asymmetry" in terms:  # keep |delta| < beta + gamma for the random element
        terms["asymmetry"] *= float(beta + gamma)
    if "play" in terms:  # play in units of x: a fraction of the latent amplitude
        gain = abs(np.polyval(args[0], 1j * omega) / np.polyval(args[1], 1j * omega))
        terms["play"] *= float(abs(amp) * gain)
    n, sub = 160, 2
    core: Any = _core  # the random case is a tuple of mixed types: checked at run time, not statically
    ref: Any = reference
    xr, wr, yr = core.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms)
    xn, wn, yn = ref.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms)
    # Same stages in the same order as design.md 9.4; the two differ only in the rounding of the short
    # dot products and of libm's sin/cos/pow/tanh/exp (as the plain simulation's parity test, which
    # measures <= 3e-15 of the peak).  The play's step mode is a comparison on rounded values, but none
    # of these seeded cases sits on a tie.  1e-11 of the peak leaves a wide margin and still catches any
    # difference of method.
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert r.shape == p.shape == (n,)
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * _scale(p))
    # The sampled-input path, on a noisy cosine held constant at the end.
    rng = np.random.default_rng([708, order, seed])
    u = amp * np.cos(omega * np.arange(n) * dt) + 0.05 * rng.standard_normal(n)
    u[-10:] = u[-11]
    xr, wr, yr = core.simulate_sampled(*args, u, dt, sub, terms=terms)
    xn, wn, yn = ref.simulate_sampled(*args, u, dt, sub, terms=terms)
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * _scale(p))


@pytest.mark.parametrize("core", [_core, reference], ids=["rust", "numpy"])
def test_core_term_errors(core: Any) -> None:
    args = (np.array([1.0]), np.array([1.0, 1.0]), 0.0, 1.0, 1.0, 0.2, 1.5, 0.0, 1.0, 2.0, 0.05, 50, 1)
    cases: list[tuple[dict[str, float], type[Exception], str]] = [
        ({"spring": 1.0}, InvalidParameterError, "unknown term"),
        ({"viscous": float("nan")}, NonFiniteError, "viscous"),
        ({"sensor_lag": -1.0}, InvalidParameterError, "sensor_lag"),
        ({"play": -1.0}, InvalidParameterError, "play"),
        ({"coulomb_smoothing": 0.0}, InvalidParameterError, "coulomb_smoothing"),
        ({"asymmetry": 1.2}, InvalidParameterError, "beta \\+ gamma"),
    ]
    for terms, error, text in cases:
        with pytest.raises(error, match=text):
            core.simulate_sine(*args, terms=terms)
    # The plant's own checks still come first.
    with pytest.raises(InvalidParameterError, match="mu"):
        core.simulate_sine(*args[:6], 0.5, *args[7:], terms={"spring": 1.0})
    # An empty mapping is the augmented path with no term: y = w.
    x, w, y = core.simulate_sine(*args, terms={})
    assert_array_equal(y, w)


# --------------------------------------------------------------------------------------------------
# Closed forms
# --------------------------------------------------------------------------------------------------

PLAN = SinePlan([1.3, 4.0], [1.5, -0.8], settle_periods=1, periods=2, samples_per_period=64, substeps=3)


def _pairs(terms: tuple[Term, ...], plan: SinePlan = PLAN) -> list[tuple[bw.Recording, bw.Recording]]:
    return list(zip(bw.simulate(_plant(), plan), bw.simulate(_plant(terms), plan)))


def test_output_terms_add_exactly_at_the_samples() -> None:
    y0, k, c, m, f, eps = 0.25, 0.6, -0.07, 0.02, 0.3, 0.05
    terms = (Offset(y0), Stiffness(k), Viscous(c), Inertia(m), Coulomb(f, smoothing=eps))
    for plain, aug in _pairs(terms):
        # No term needs a state: x and w come from the untouched plain integrator, bit for bit.
        assert_array_equal(aug.x, plain.x)
        assert_array_equal(aug.w, plain.w)
        amp, om, t = plain.amplitude, plain.frequency, plain.t
        u, udot, uddot = amp * np.cos(om * t), -amp * om * np.sin(om * t), -amp * om**2 * np.cos(om * t)
        expected = y0 + k * u + c * udot + m * uddot + f * np.tanh(udot / (eps * abs(amp) * om))
        # The only difference is rounding: y0 + (w + terms) against w + (terms) - a few ulps of |y|.
        assert_allclose(aug.y - plain.y, expected, rtol=0, atol=1e-14 * _scale(aug.y))
    # One term at a time adds exactly its own contribution.
    for term, part in ((Offset(y0), lambda u, ud, udd: y0 + 0 * u), (Inertia(m), lambda u, ud, udd: m * udd)):
        for plain, aug in _pairs((term,)):
            amp, om, t = plain.amplitude, plain.frequency, plain.t
            u = amp * np.cos(om * t)
            want = part(u, -amp * om * np.sin(om * t), -(om**2) * u)  # type: ignore[no-untyped-call]
            assert_allclose(aug.y - plain.y, want, rtol=0, atol=1e-14 * _scale(aug.y))


def test_output_terms_on_a_sampled_input_use_the_interpolant() -> None:
    # Catmull-Rom reproduces a quadratic exactly between interior knots: u = t^2 - 1 has udot = 2 t and
    # uddot = 2 there (the knots' right-hand values); Vmax is the peak slope of the interpolant.
    dt = 0.01
    t = np.arange(200) * dt
    u = t**2 - 1.0
    k, c, m = 0.5, 0.2, 0.1
    plant = _plant((Stiffness(k), Viscous(c), Inertia(m), Offset(-0.2)))
    x, w, y = bw.simulate_input(plant, t, u, substeps=2, output=True)
    xp, wp = bw.simulate_input(_plant(), t, u, substeps=2)
    assert_array_equal(x, xp)
    assert_array_equal(w, wp)
    inner = slice(1, -2)
    want = -0.2 + k * u + c * 2 * t + m * 2.0
    # uddot of the interpolant divides sample differences by dt^2 = 1e-4: its rounding is about
    # 16 max|u| eps / dt^2 = 1e-10 (times m = 0.1); the rest rounds at 1e-15.
    assert_allclose((y - w)[inner], want[inner], rtol=0, atol=1e-10)
    # Friction saturates at +f where the input moves up at more than a few eps Vmax.
    x, w, y = bw.simulate_input(_plant((Coulomb(0.4),)), t, u, output=True)
    moving = (2 * t > 0.4 * t[-1])[inner]  # udot > 0.2 Vmax: tanh(20) = 1 to 1e-17
    assert_allclose((y - w)[inner][moving], 0.4, rtol=1e-6)
    # Both backends agree here too.
    yn = bw.simulate_input(_plant((Coulomb(0.4),)), t, u, output=True, backend="numpy")[2]
    assert_allclose(y, yn, rtol=1e-12, atol=1e-12)


def test_sensor_lag_is_a_first_order_filter_of_the_output() -> None:
    # A fine grid, so that lsim's linear interpolation of F between samples is accurate, and no input
    # delay (whose switch-on at t = delay would put a kink in F between two samples).
    tau = 0.09
    plan = SinePlan([2.0, 7.0], [1.0, 0.5], settle_periods=0, periods=3, samples_per_period=512, substeps=2)
    inner: tuple[Term, ...] = (Stiffness(0.3), Viscous(0.05))
    lin, hyst = TransferFunction([1.0, 2.0], [0.1, 0.7, 2.0]), BoucWen(0.9, 0.3, 1.6)
    plain_recs = bw.simulate(WienerPlant(lin, hyst, inner), plan)
    lagged_recs = bw.simulate(WienerPlant(lin, hyst, (*inner, SensorLag(tau))), plan)
    for plain, lagged in zip(plain_recs, lagged_recs):
        assert_array_equal(lagged.w, plain.w)  # the lag does not feed back
        _, expected, _ = signal.lsim(([1.0], [tau, 1.0]), plain.y, plain.t, X0=[0.0])
        # lsim holds F linear between samples: an input error of at most dt^2/8 max|F''| (max|F''| dt^2
        # from the second differences), which the lag (positive impulse response, unit gain) does not
        # enlarge; the simulation uses F at its own stage times.  Twice that bound, plus the RK4 error
        # of the Bouc-Wen element (1e-6 of the peak).  Measured: a fifth of it, falling 4x per halving
        # of dt (lsim's second order).
        bound = 2 * float(np.max(np.abs(np.diff(plain.y, 2)))) / 8 + 1e-6 * _scale(plain.y)
        err = float(np.max(np.abs(lagged.y - expected)))
        assert err < bound
        assert _scale(lagged.y - plain.y) > 100 * bound  # and the lag is far from negligible
        assert lagged.y[0] == 0.0  # ys(0) = 0


def test_sensor_lag_matches_the_exact_response_from_rest() -> None:
    # A hysteresis so weak (beta = 1e-12) that w = w0 + x - x(0) and a static G: F is a constant plus a
    # sinusoid, whose lag from ys(0) = 0 is known in closed form.  The step is exact for a quadratic F:
    # third order (design.md 9.4), on both sides of the series switch at h/tau = 1 and for a sensor far
    # faster than the step (h/tau = 20, where explicit RK4 would blow up).
    g, w0, k, c, amp, om = 1.5, 0.1, 0.4, 0.2, 0.8, 3.0

    def exact(t: np.ndarray, tau: float) -> np.ndarray:
        # F = (w0 - g U) + (g + k) U cos(om t) - c U om sin(om t) = c0 + Re(z e^{i om t})
        c0, z = w0 - g * amp, (g + k) * amp + 1j * c * amp * om

        def steady(tt: Any) -> Any:
            return np.real(z * np.exp(1j * om * tt) / (1 + 1j * om * tau))

        out: np.ndarray = c0 * (1 - np.exp(-t / tau)) + steady(t) - steady(0.0) * np.exp(-t / tau)
        return out

    def error(p: int, ratio: float) -> float:
        tau = TWO_PI / om / p / ratio
        terms = (Stiffness(k), Viscous(c), SensorLag(tau))
        plant = WienerPlant(TransferFunction([g], [1.0]), BoucWen(1e-12, 0.0, 2.0, 1.0, w0), terms)
        plan = SinePlan([om], amp, settle_periods=0, periods=2, samples_per_period=p, substeps=1)
        (rec,) = bw.simulate(plant, plan)
        return float(np.max(np.abs(rec.y - exact(rec.t, tau))))

    for ratio in (20.0, 2.0, 0.667, 0.1):
        coarse, fine = error(64, ratio), error(128, ratio)
        # Measured at 64 samples per period: 4.6e-6 (h/tau = 20) down to 1.7e-7 (0.1), of a peak of 1.8.
        assert coarse < 2e-5
        assert coarse / fine > 6.0  # third order: 8x per halving of h


def _play_operator(x: np.ndarray, b: float, xp0: float = 0.0) -> np.ndarray:
    """The play operator applied sample by sample: ``xp_k = clamp(xp_{k-1}, x_k - b, x_k + b)``."""
    out = np.empty_like(x)
    xp = xp0
    for k, xk in enumerate(x):
        xp = min(max(xp, xk - b), xk + b)
        out[k] = xp
    return out


def test_play_follows_the_play_operator() -> None:
    # beta, gamma tiny: w = w0 + alpha (xp - xp(0)) to 1e-12, so w shows xp itself.
    b, alpha, w0 = 0.3, 1.7, 0.05
    plant = WienerPlant(
        TransferFunction([1.0], [0.4, 1.0], 0.0), BoucWen(1e-12, 0.0, 2.0, alpha, w0), (Play(b),)
    )
    plan = SinePlan([1.0, 5.0], [1.0, 2.0], settle_periods=0, periods=3, samples_per_period=2000, substeps=1)
    for rec in bw.simulate(plant, plan):
        assert rec.x is not None and rec.w is not None
        xp = _play_operator(rec.x, b)
        # The sampled operator misses at most the x travel between a sample and a turning point,
        # max|xddot| dt^2 / 2; the simulation's play is exact at the step ends except in the step
        # holding a reversal (same order).  Bound: max|second difference of x| (measured: 1/20 of it).
        bound = float(np.max(np.abs(np.diff(rec.x, 2))))
        assert_allclose((rec.w - w0) / alpha, xp, rtol=0, atol=bound)
        # The play is really engaged and dwelling: xp differs from x by up to b.
        assert float(np.max(np.abs(rec.x - xp))) == pytest.approx(b, rel=1e-3)


def test_play_drives_the_hysteresis_along_the_played_path() -> None:
    # With a real hysteresis: w of the simulation against the rate-independent Bouc-Wen map integrated
    # along the directly played xp (RK4 in xp, 8 steps per sample increment).
    b = 0.25
    hyst = BoucWen(1.0, 0.4, 1.5, 1.0, 0.0)
    plant = WienerPlant(TransferFunction([1.2], [0.5, 1.0], 0.1), hyst, (Play(b), Asymmetry(0.5)))
    plan = SinePlan([2.0], [1.5], settle_periods=0, periods=3, samples_per_period=1024, substeps=2)
    (rec,) = bw.simulate(plant, plan)
    assert rec.x is not None and rec.w is not None
    xp = _play_operator(rec.x, b)

    def rate(dxp: float, w: float) -> float:
        wmu = abs(w) ** 1.5
        return float(dxp * (1.0 - wmu * (1.0 * np.sign(dxp * w) + 0.4 + 0.5 * np.sign(w))))

    w = np.zeros_like(xp)
    for k in range(1, xp.size):
        d = (xp[k] - xp[k - 1]) / 8
        wk = w[k - 1]
        for _ in range(8):
            k1 = rate(d, wk)
            k2 = rate(d, wk + k1 / 2)
            k3 = rate(d, wk + k2 / 2)
            k4 = rate(d, wk + k3)
            wk += (k1 + 2 * k2 + 2 * k3 + k4) / 6
        w[k] = wk
    # Both are second order at the reversals (the sampled operator's turning points, the simulation's
    # reversal steps); measured 7e-6 of the peak on this grid.  1e-4 still catches a wrong sign of
    # delta (a 0.5 change of a saturation level) or a play that does not dwell.
    assert_allclose(rec.w, w, rtol=0, atol=1e-4 * _scale(w))


def test_asymmetry_saturates_at_its_two_levels() -> None:
    # alpha = 1, a large slow sine through a static gain: w reaches (beta + gamma +- delta)^(-1/mu).
    beta, gamma, mu, delta = 1.0, 0.5, 2.5, 0.7
    plant = WienerPlant(TransferFunction([1.0], [1.0]), BoucWen(beta, gamma, mu), (Asymmetry(delta),))
    plan = SinePlan([1.0], [40.0], settle_periods=0, periods=2, samples_per_period=4000, substeps=2)
    (rec,) = bw.simulate(plant, plan)
    assert rec.w is not None
    # Near a level dw/dx = -mu (level)^(mu-1) (beta+gamma+-delta) (w - level): the approach is
    # exponential in x, so a travel of 80 reaches it to rounding (measured 1.4e-15); 1e-9 leaves room
    # for the RK4 error and still tells apart a level off by a wrong sign or factor of delta.
    top, bottom = (beta + gamma + delta) ** (-1 / mu), -((beta + gamma - delta) ** (-1 / mu))
    assert float(np.max(rec.w)) == pytest.approx(top, rel=1e-9)
    assert float(np.min(rec.w)) == pytest.approx(bottom, rel=1e-9)
    # The plain element's levels are symmetric: the asymmetry really moved them apart.
    assert abs(top + bottom) > 0.1


# --------------------------------------------------------------------------------------------------
# The plain path is untouched
# --------------------------------------------------------------------------------------------------

#: sha256 of the float64 bytes of (x, w) from the Rust core at the base commit a62de29 (before terms),
#: for the sine and the sampled inputs of ``_frozen_case`` (rust/simulate.rs's plain path, built with the
#: release profile and printed from an example binary on x86_64 Linux; the bits depend on libm's
#: sin/cos/pow, so another platform's libm may need its own fixture).  Should a change of the plain
#: integrator ever be meant to alter its rounding, this is the test to update, deliberately.
FROZEN_SHA256 = {
    "sine": "7ec9565f0d6260902713b76fe0605073a5e9062fdc99efaf98d251811c251b96",
    "sampled": "36d5c06606187a04ab67a5e9b9735102857a5d8796deb813fb27584ff4d61b99",
}


def _frozen_case() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    args = (np.array([0.8, 1.0]), np.array([0.5, 0.6, 1.0]), 0.07, 1.3, 0.9, 0.3, 1.7, 0.05)
    omega = 2.5
    dt = TWO_PI / omega / 32.0
    k = np.arange(96, dtype=np.float64)
    u = np.array([math.sin(0.3 * kk) + 0.01 * kk for kk in k])
    return {
        "sine": _core.simulate_sine(*args, 1.4, omega, dt, 96, 3),
        "sampled": _core.simulate_sampled(*args, u, dt, 3),
    }


def _digest(x: np.ndarray, w: np.ndarray) -> str:
    return hashlib.sha256(x.astype("<f8").tobytes() + w.astype("<f8").tobytes()).hexdigest()


def test_a_plant_without_terms_simulates_bit_identically() -> None:
    for name, (x, w) in _frozen_case().items():
        assert _digest(x, w) == FROZEN_SHA256[name], name
    # simulate() of a plain plant returns exactly the plain core's signals, and y = w.
    plant = _plant()
    plan = SinePlan([2.0], [1.1], settle_periods=0, periods=2, samples_per_period=32, substeps=2)
    (rec,) = bw.simulate(plant, plan)
    lin, h = plant.linear, plant.hysteresis
    args = (lin.num, lin.den, lin.delay, h.alpha, h.beta, h.gamma, h.mu, h.w0, 1.1, 2.0, rec.dt, 64, 2)
    x, w = _core.simulate_sine(*args)
    assert rec.x is not None and rec.w is not None
    assert_array_equal(rec.x, x)
    assert_array_equal(rec.w, w)
    assert_array_equal(rec.y, w)


def test_zero_terms_reproduce_the_plain_simulation() -> None:
    # Play(0) is the identity and Asymmetry(0) nothing (the plain integrator, as no term needs a state);
    # a vanishing lag forces the augmented integrator, which with delta = b = 0 is the plain one up to
    # rounding, and its y is F after the first sample (ys(0) = 0).
    plain = bw.simulate(_plant(), PLAN)
    for terms in ((Play(0.0), Asymmetry(0.0)), (SensorLag(1e-300),)):
        for p, a in zip(plain, bw.simulate(_plant(terms), PLAN)):
            assert a.x is not None and p.x is not None and a.w is not None and p.w is not None
            assert_allclose(a.x, p.x, rtol=0, atol=1e-13 * _scale(p.x))
            assert_allclose(a.w, p.w, rtol=0, atol=1e-13 * _scale(p.w))
            assert_allclose(a.y[1:], p.y[1:], rtol=0, atol=1e-13 * _scale(p.y))


def test_registry_lookups_refuse_unknown_names_and_places_by_name() -> None:
    # A wrong term name or place is the library's InvalidParameterError, not a KeyError or a bare ValueError.
    with pytest.raises(InvalidParameterError, match="unknown term 'nope'"):
        bw.terms.physical_value("nope", 1.0)
    with pytest.raises(InvalidParameterError, match="not a Place"):
        bw.terms.Viscous.at("z")  # type: ignore[arg-type]
    assert bw.terms.physical_value("viscous", 0.1) and not bw.terms.physical_value("viscous", -0.1)


def test_every_terms_annotations_resolve_from_its_published_module() -> None:
    """Each class is published as ``bouc_wen_id.terms.<Name>`` (its ``__module__``), so ``get_type_hints``
    resolves its string annotations there: every name they use (ClassVar, Callable, ...) must be found
    (a NameError before ClassVar and Callable were importable from the package)."""
    import typing

    from bouc_wen_id import terms as T

    for cls in [*T.TERMS.values(), T.Term, T.StartContext]:
        assert cls.__module__ == "bouc_wen_id.terms", cls
        hints = typing.get_type_hints(cls)
        assert hints, cls  # each has annotated attributes: the resolution ran

"""The diagnosis across conditions (bouc_wen_id.diagnosis.across, issue 18): one named structure for several
conditions, its values free per condition.

The conditions are made by the bench's independent generator (benches/generator.py: G integrated exactly,
the hysteresis by its own RK4, not the library's simulator), one plant, an effect whose value changes with
the condition, a noise stream per condition from a seed.
"""

from __future__ import annotations

import importlib
import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.across import smoothness

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
G: Any = importlib.import_module("generator")

#: A few candidates keep the tests short; the rivals of viscous damping on u are among them.
CANDS = ("offset", "stiffness", "viscous", "viscous@x", "asymmetry", "stiffness@x")
CONDITIONS = (0.0, 1.0, 2.0, 3.0)


def _conditions(seed: int, sizes: tuple[float, ...]) -> tuple[list[list[Any]], np.ndarray]:
    """Recordings of one plant with viscous damping on u sized ``sizes`` averaged-noise sd per condition
    (0: absent); (groups, the true values)."""
    p = G.make_plant(seed)
    b = G.base(p)
    plain = G.run(p, G.Effect(), shared=b)
    unit = float(G.contribution(p, G.Effect("viscous", "u", np.ones(1)), plain, b)[0])
    values = np.asarray(sizes) / unit
    y = G.run(p, G.Effect("viscous", "u", values), shared=b)
    return [G.recordings(p, y[k], 100 * seed + k) for k in range(values.size)], values


def _run(groups: list[list[Any]], **kw: Any) -> tuple[bw.AcrossDiagnosis, list[bw.Diagnosis]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=CANDS) for g in groups]
        a = bw.diagnose_across(groups, CONDITIONS[: len(groups)], candidates=CANDS, per_condition=own, **kw)
    return a, own


def test_a_term_that_moves_linearly_with_the_condition_is_one_structure() -> None:
    # Weak at the first condition: its own diagnosis does not name it (asserted: the premise), so
    # per-condition selection would tell different stories; the joint selection names it at every condition.
    groups, truth = _conditions(1, (0.05, 0.15, 0.25, 0.35))
    a, own = _run(groups)
    own_named = [tuple(t.term for t in d.named) for d in own]
    assert any("viscous" not in n for n in own_named), own_named  # per-condition: not one story
    assert a.named == ("viscous",), a.verdict
    (t,) = a.terms
    # Each condition's value is the truth within 3 se (its se honest), and the values move linearly.
    z = (np.asarray(t.values) - truth) / np.asarray(t.standard_errors)
    assert np.all(np.abs(z) < 3.0), z
    assert t.smooth_degree == 1, t.smooth_p  # not one shared value, a line in the condition
    assert not t.shared
    assert t.present[-1] and not t.present[0]  # the weakest condition does not ask for it on its own
    assert "viscous damping" in a.verdict
    for c in a.conditions:  # the joint structure is no worse held out than the condition's own one
        assert c.held_out_joint <= c.held_out_per_level * 1.05
    d = a.to_dict()
    assert d["terms"][0]["smooth_degree"] == 1 and len(d["conditions"]) == 4


def test_a_term_present_only_at_some_conditions_is_reported_so() -> None:
    groups, truth = _conditions(2, (0.0, 0.0, 1.0, 2.0))
    a, _ = _run(groups)
    assert a.named == ("viscous",), a.verdict
    (t,) = a.terms
    assert t.present == (False, False, True, True), t.p_present
    assert not t.everywhere
    # Where it is absent its value is 0 within its se; where present, the truth.
    z = (np.asarray(t.values) - truth) / np.asarray(t.standard_errors)
    assert np.all(np.abs(z) < 3.0), z
    assert "needed only at 2, 3" in a.verdict
    assert t.smooth_degree != 0  # not one shared value


def test_null_conditions_name_nothing() -> None:
    # No condition variable given (0, 1, 2), no per-condition diagnoses: each group prepared and fitted here.
    groups, _ = _conditions(3, (0.0, 0.0, 0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, candidates=CANDS)
    assert a.named == () and a.terms == ()
    assert [c.condition for c in a.conditions] == [0.0, 1.0, 2.0]
    assert all(c.per_level_terms is None for c in a.conditions)
    # Nothing named because the plain model fits at every condition: said as diagnose says it.
    assert (
        a.status == "adequate"
        and "adequate: the plain Wiener-Bouc-Wen model fits at the noise floor" in a.verdict
    )
    assert len(a.steps) == 1 and a.steps[0].chosen is None
    assert all(math.isfinite(c.final_chi2_dof) for c in a.conditions)


def test_smoothness_recognises_the_polynomial_order() -> None:
    rng = np.random.default_rng(5)
    c = np.linspace(0.0, 1.0, 6)
    se = np.full(c.size, 0.01)
    line = 2.0 + 3.0 * c + rng.normal(0.0, 0.01, c.size)
    p = smoothness(c, line, se)
    assert p[0] < 1e-6 and p[1] > 0.01
    bent = 2.0 + 3.0 * c * c + rng.normal(0.0, 0.01, c.size)
    q = smoothness(c, bent, se)
    assert q[1] < 1e-6 and q[2] > 0.01
    assert smoothness(c, line, np.zeros(c.size)) == ()  # no se: no test


def test_bad_input_is_refused_with_a_named_error() -> None:
    groups, _ = _conditions(3, (0.0, 0.0))
    with pytest.raises(bw.InvalidParameterError, match="at least 2 conditions"):
        bw.diagnose_across(groups[:1])
    with pytest.raises(bw.InvalidParameterError, match="distinct"):
        bw.diagnose_across(groups, [1.0, 1.0])
    with pytest.raises(bw.InvalidParameterError, match="values for"):
        bw.diagnose_across(groups, [1.0, 2.0, 3.0])
    with pytest.raises(bw.InvalidParameterError, match="candidates"):
        bw.diagnose_across(groups, candidates=["no_such_term"])


def test_the_command_line_reads_groups_and_writes_the_json(tmp_path: Path, capsys: Any) -> None:
    from bouc_wen_id.cli import main
    from bouc_wen_id.io import save_recordings

    groups, _ = _conditions(2, (0.0, 2.0))
    dirs = []
    for k, g in enumerate(groups):
        save_recordings(tmp_path / f"c{k}", g)
        dirs.append(str(tmp_path / f"c{k}"))
    out = tmp_path / "across.json"
    argv = ["diagnose-across", "--group", "0", dirs[0], "--group", "0.5", dirs[1]]
    argv += ["--candidates", "viscous,offset", "--no-held-out", "--json", str(out)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(argv) == 0
    d = json.loads(out.read_text())
    assert d["format"] == "bouc_wen_id.diagnosis_across"
    assert [c["condition"] for c in d["conditions"]] == [0.0, 0.5]
    assert "across 2 conditions" in capsys.readouterr().out
    # One group is no comparison across conditions: a named error, exit 2.
    assert main(["diagnose-across", "--group", "0", dirs[0]]) == 2
    assert "at least 2 conditions" in capsys.readouterr().err
    assert main(["diagnose-across", "--group", "x", dirs[0], "--group", "1", dirs[1]]) == 2


def test_the_json_never_replaces_a_users_file_unasked(tmp_path: Path, capsys: Any) -> None:
    """``--json`` onto an existing file (a recording, say) or a folder is refused before any diagnosis, the
    file left as it was; ``--overwrite`` replaces a file (and never a folder)."""
    from bouc_wen_id.cli import main

    mine = tmp_path / "mine.csv"
    mine.write_text("t,u,y\n0,1,2\n")
    argv = ["diagnose-across", "--group", "0", "nowhere_a", "--group", "1", "nowhere_b"]
    assert main([*argv, "--json", str(mine)]) == 2
    err = capsys.readouterr().err
    assert f"--json {mine} exists; pass --overwrite" in err
    assert mine.read_text() == "t,u,y\n0,1,2\n"
    assert main([*argv, "--json", str(tmp_path), "--overwrite"]) == 2
    assert "is not a regular file" in capsys.readouterr().err

"""The diagnosis bench's ``--only`` filter (benches/diagnosis.py: :func:`kept`): an effect's name keeps every
place of it, ``name@place`` one place, so one at-x row can be rerun alone with its own seeds."""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("diagnosis")


def _jobs() -> list[Any]:
    return list(bench.new_jobs(argparse.Namespace(quick=False, cases=3, null=2, seed=0)))


def test_a_placed_name_keeps_that_place_only_with_the_seeds_of_the_full_run() -> None:
    jobs = _jobs()
    at_x = bench.kept(jobs, "viscous@x")
    assert at_x and {(j[1], j[2]) for j in at_x} == {("viscous", "x")}
    full = [j for j in jobs if j[1] == "viscous" and j[2] == "x"]
    assert at_x == full  # the same seeds as in the run of every row
    both = bench.kept(jobs, "viscous")
    assert {j[2] for j in both} == {"u", "x"} and len(both) == 2 * len(at_x)


def test_names_and_nulls_combine() -> None:
    jobs = _jobs()
    got = bench.kept(jobs, "null,stiffness@u,sensor_lag")
    assert {j[0] for j in got if j[1] is None} == {"null"} and sum(j[1] is None for j in got) == 2
    assert {(j[1], j[2]) for j in got if j[1] is not None} == {("stiffness", "u"), ("sensor_lag", "")}
    assert bench.kept(jobs, "nothing_by_that_name") == []


def test_an_entry_that_keeps_no_row_is_named() -> None:
    jobs = _jobs()
    assert bench.unmatched(jobs, "viscous@x,bogus@nowhere,viscous@q,null") == ["bogus@nowhere", "viscous@q"]
    assert bench.unmatched(jobs, "viscous,stiffness@u,null") == []

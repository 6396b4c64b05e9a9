"""The package's import graph runs one way: value types never reach the oracle or the CLI.

Read from the source (every import, at module level or inside a function, except those under
``TYPE_CHECKING``), so that a lazy import cannot hide a wrong dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import bouc_wen_id
import pytest

PACKAGE = Path(bouc_wen_id.__file__).parent

#: Modules that hold values and their checks: they must not depend on the NumPy reference (the oracle that
#: checks the Rust core), on the backend choice, on the estimators or on the command line.
VALUE_MODULES = (
    "errors",
    "validation",
    "model",
    "measurement",
    "result",
    "io",
    "io._common",
    "io._header",
    "io._csv",
    "io._text",
    "io._npz",
    "io._matv5",
    "io._mat",
    "io._containers",
    "io._tdms",
    "io._hdf5",
    "io._load",
    "terms",
    "signal",
    "signal._sine",
    "signal._windows",
    "signal._segments",
    "signal._averaging",
    "signal._harmonic_ls",
)
#: The NumPy oracle: the reference and its extensions for the augmented model (design.md 9).
ORACLE = ("reference", "reference_terms", "reference_path", "reference_augmented")
FORBIDDEN = (*ORACLE, "cli", "_backend", "identification", "estimators", "augmented", "diagnosis")


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(path: Path, name: str) -> set[str]:
    """Package modules imported by the module at ``path`` (named ``name``), outside TYPE_CHECKING."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    if path.name == "__init__.py":
        package = name.split(".") if name else []
    else:
        package = name.split(".")[:-1]
    out: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            child: ast.AST
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
            stem = [*base, *(node.module.split(".") if node.module else [])]
            if node.module:
                out.add(".".join(stem))
            for alias in node.names:  # ``from . import reference`` imports a module
                out.add(".".join([*stem, alias.name]))
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("bouc_wen_id."):
            out.add(str(node.module)[len("bouc_wen_id.") :])
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return out


def _graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    return {name: {m for m in _imports(path, name) if m in files} for name, path in files.items()}


def _reach(graph: dict[str, set[str]], start: str) -> set[str]:
    seen: set[str] = set()
    todo = [start]
    while todo:
        for nxt in graph[todo.pop()]:
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


@pytest.mark.parametrize("module", VALUE_MODULES)
def test_value_modules_do_not_reach_the_oracle_or_the_cli(module: str) -> None:
    graph = _graph()
    assert module in graph, f"{module} is not a module of the package: update VALUE_MODULES"
    bad = sorted(_reach(graph, module) & set(FORBIDDEN))
    assert not bad, f"{module} imports (directly or through others) {bad}"


def test_import_graph_has_no_cycle() -> None:
    graph = _graph()
    # A package's __init__ re-exports its children; the edge child -> package is the only one allowed back.
    for name in graph:
        for parent in (p for p in graph if name.startswith(p + ".") and p):
            graph[name].discard(parent)
    graph.pop("", None)
    for deps in graph.values():
        deps.discard("")
    for name in graph:
        assert name not in _reach(graph, name), f"{name} imports itself through {sorted(_reach(graph, name))}"


@pytest.mark.parametrize("module", ORACLE)
def test_the_oracle_reaches_only_errors_validation_and_itself(module: str) -> None:
    assert _reach(_graph(), module) <= {"errors", "validation", *ORACLE}

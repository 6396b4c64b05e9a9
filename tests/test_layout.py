"""The package's layout: one door to the numerics, an oracle apart, an import graph that runs one way, and
rooms of a readable size.

Everything is read from the source with :mod:`ast` (every import, at module level or inside a function,
except those under ``TYPE_CHECKING``; ``importlib.import_module("bouc_wen_id.x")`` too), so that a lazy
import cannot hide a dependency.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

import bouc_wen_id
import pytest

PACKAGE = Path(bouc_wen_id.__file__).parent

#: The one door to the compiled extension and to the NumPy oracle.
DOOR = "_backend"
#: The oracle: the NumPy reference that holds the Rust core to account (a package, one module per Rust file).
ORACLE = "reference"
#: Modules besides the door that may name the extension, and why.
MAY_NAME_CORE = {"": "__init__ reads the version: from ._core import __version__"}
#: Modules besides the door that may import the oracle, and why.
MAY_IMPORT_ORACLE = {"": "__init__ re-exports it for users as bouc_wen_id.reference (public API)"}

#: Modules that hold values and their checks: they must not reach, even through others, the oracle, the
#: backend choice, the estimators, the diagnosis or the command line.
VALUE_MODULES = ("errors", "validation", "terms", "model", "result")
#: The lab preprocessing asks the door for its kernels, but never reaches the estimators, the diagnosis or
#: the command line, nor the oracle other than through the door.
NUMERIC_MODULES = (
    "io",
    "measurement",
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
    "signal",
    "signal._sine",
    "signal._windows",
    "signal._segments",
    "signal._averaging",
    "signal._harmonic_ls",
)
UPPER = ("cli", "identification", "estimators", "augmented", "diagnosis", "batch", "planning")

#: A dotted module path of the package, as ``importlib.import_module`` takes it.
_DOTTED = re.compile(r"bouc_wen_id(\.[A-Za-z_][A-Za-z0-9_]*)+")

#: Largest module, in lines.
MODULE_LINES_MAX = 1000
#: Largest function or method, in lines (from ``def`` to its last line, docstring included).
FUNCTION_LINES_MAX = 100
#: Functions over FUNCTION_LINES_MAX in files other helpers of this round are splitting (issue 17); the
#: integrator empties this list after merging them.  Each entry is ``module:qualified name``.
KNOWN_LONG_FUNCTIONS_PENDING_MERGE = frozenset(
    {
        "diagnosis.run:diagnose",
    }
)
#: Modules over MODULE_LINES_MAX that other helpers are splitting (issue 17); emptied after the merge.
KNOWN_LONG_MODULES_PENDING_MERGE: frozenset[str] = frozenset()
#: Modules other helpers of this round are routing through the door (issue 17/18): they still name
#: ``_core`` today.  Emptied after the merge.
KNOWN_CORE_USERS_PENDING_MERGE: frozenset[str] = frozenset()


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


@cache
def _files() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@cache
def _tree(name: str) -> ast.Module:
    return ast.parse(_files()[name].read_text(encoding="utf-8"))


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _runtime_nodes(tree: ast.AST) -> list[ast.AST]:
    """Every node outside ``if TYPE_CHECKING:`` blocks (their ``else`` kept)."""
    out: list[ast.AST] = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for branch in node.orelse:
                visit(branch)
            return
        out.append(node)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return out


def _imports_in(tree: ast.AST, package: list[str]) -> set[str]:
    """Names (dotted, relative to the package) a module of ``package`` imports at run time.

    ``from . import x`` imports ``x``; ``from .x import y`` imports ``x`` and ``x.y`` (which is kept only if
    it is a module); ``import bouc_wen_id.x`` and ``importlib.import_module("bouc_wen_id.x")`` import ``x``.
    """
    out: set[str] = set()
    for node in _runtime_nodes(tree):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
            stem = [*base, *(node.module.split(".") if node.module else [])]
            if node.module:
                out.add(".".join(stem))
            out.update(".".join([*stem, alias.name]) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "bouc_wen_id":
            stem = str(node.module).split(".")[1:]
            out.add(".".join(stem))
            out.update(".".join([*stem, alias.name]) for alias in node.names)
        elif isinstance(node, ast.Import):
            out.update(a.name[len("bouc_wen_id.") :] for a in node.names if a.name.startswith("bouc_wen_id."))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and _DOTTED.fullmatch(node.value):
            out.add(node.value[len("bouc_wen_id.") :])  # importlib.import_module("bouc_wen_id.x")
    return out


def _imports(name: str) -> set[str]:
    here = name.split(".") if name else []
    return _imports_in(_tree(name), here if _files()[name].name == "__init__.py" else here[:-1])


@cache
def _graph() -> dict[str, frozenset[str]]:
    """Module -> package modules it imports at run time (an edge from a child to its own package, which
    re-exports it, is dropped: that is how a package's ``__init__`` works, not a cycle)."""
    files = _files()
    graph: dict[str, frozenset[str]] = {}
    for name in files:
        deps = {m for m in _imports(name) if m in files and m != name}
        deps -= {p for p in files if p != name and (p == "" or name.startswith(p + "."))}
        graph[name] = frozenset(deps)
    return graph


def _reach(start: str, *, stop_at: frozenset[str] = frozenset()) -> set[str]:
    """Modules reachable from ``start``, not walking on past those in ``stop_at``."""
    graph = _graph()
    seen: set[str] = set()
    todo = [start]
    while todo:
        for nxt in graph[todo.pop()]:
            if nxt not in seen:
                seen.add(nxt)
                if nxt not in stop_at:
                    todo.append(nxt)
    return seen


def _in_oracle(module: str) -> bool:
    return module == ORACLE or module.startswith(ORACLE + ".")


def _names_core(tree: ast.AST) -> list[int]:
    """Lines where a module names the extension ``_core``: an import, a name, an attribute or a dotted
    string (``TYPE_CHECKING`` blocks included: naming it is the offence)."""
    hits = []
    for node in ast.walk(tree):
        found = (
            (isinstance(node, ast.ImportFrom) and "_core" in (node.module or "").split("."))
            or (
                isinstance(node, (ast.ImportFrom, ast.Import))
                and any(a.name.split(".")[-1] == "_core" for a in node.names)
            )
            or (isinstance(node, ast.Name) and node.id == "_core")
            or (isinstance(node, ast.Attribute) and node.attr == "_core")
            or (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and node.value.endswith("._core")
            )
        )
        if found:
            hits.append(int(getattr(node, "lineno", 0)))
    return hits


LAZY = """
import importlib
from typing import TYPE_CHECKING
if TYPE_CHECKING:
    from . import model
def f():
    from . import _core
    from .reference import augmented
    return importlib.import_module("bouc_wen_id.signal._sine")
"""


def test_the_checks_see_lazy_and_importlib_imports() -> None:
    # The checks below are only as good as what they see: a lazy import must not hide.
    tree = ast.parse(LAZY)
    assert _names_core(tree) == [7]
    assert _imports_in(tree, []) == {"_core", "reference", "reference.augmented", "signal._sine"}
    assert _names_core(ast.parse("importlib.import_module('bouc_wen_id._core')")) == [1]


def test_only_the_door_names_the_extension() -> None:
    offenders = {
        name: hits
        for name in _files()
        if name != DOOR and name not in MAY_NAME_CORE and (hits := _names_core(_tree(name)))
    }
    pending = {n: h for n, h in offenders.items() if n in KNOWN_CORE_USERS_PENDING_MERGE}
    bad = {n: h for n, h in offenders.items() if n not in KNOWN_CORE_USERS_PENDING_MERGE}
    assert not bad, f"only {DOOR} may name _core (ask it for a typed part instead): {bad}"
    stale = KNOWN_CORE_USERS_PENDING_MERGE - set(pending)
    assert not stale, f"{sorted(stale)} no longer name _core: remove them from KNOWN_CORE_USERS_PENDING_MERGE"
    init = [n for n in ast.walk(_tree("")) if isinstance(n, ast.ImportFrom) and n.module == "_core"]
    assert [a.name for n in init for a in n.names] == ["__version__"], "__init__ takes only the version"


def test_no_production_module_imports_the_oracle() -> None:
    bad = {
        name: sorted(m for m in _graph()[name] if _in_oracle(m))
        for name in _files()
        if not _in_oracle(name) and name != DOOR and name not in MAY_IMPORT_ORACLE
    }
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"production modules import the oracle (ask {DOOR} for a part instead): {bad}"


@pytest.mark.parametrize("module", sorted(m for m in _files() if _in_oracle(m)))
def test_the_oracle_reaches_only_errors_validation_and_itself(module: str) -> None:
    outside = {m for m in _reach(module) if not _in_oracle(m)}
    assert outside <= {"errors", "validation"}, f"{module} reaches {sorted(outside)}"


@pytest.mark.parametrize("module", VALUE_MODULES)
def test_value_modules_reach_neither_numerics_nor_upper_layers(module: str) -> None:
    assert module in _graph(), f"{module} is not a module of the package: update VALUE_MODULES"
    bad = sorted(m for m in _reach(module) if m in (DOOR, *UPPER) or _in_oracle(m) or m == "_core")
    assert not bad, f"{module} imports (directly or through others) {bad}"


@pytest.mark.parametrize("module", NUMERIC_MODULES)
def test_the_lab_preprocessing_reaches_the_oracle_only_through_the_door(module: str) -> None:
    assert module in _graph(), f"{module} is not a module of the package: update NUMERIC_MODULES"
    reach = _reach(module, stop_at=frozenset({DOOR}))
    bad = sorted(m for m in reach if m in UPPER or _in_oracle(m) or m == "_core")
    assert not bad, f"{module} imports (directly or through others, the door aside) {bad}"


def test_import_graph_has_no_cycle() -> None:
    graph = _graph()
    cycles = sorted(name for name in graph if name in _reach(name))
    assert not cycles, "import cycles through: " + "; ".join(
        f"{name} -> {sorted(m for m in graph[name] if name in _reach(m))}" for name in cycles
    )


def test_no_module_over_the_size_limit() -> None:
    sizes = {name: len(path.read_text(encoding="utf-8").splitlines()) for name, path in _files().items()}
    long = {n: s for n, s in sizes.items() if s > MODULE_LINES_MAX}
    bad = {n: s for n, s in long.items() if n not in KNOWN_LONG_MODULES_PENDING_MERGE}
    assert not bad, f"modules over {MODULE_LINES_MAX} lines (split them by job): {bad}"
    stale = KNOWN_LONG_MODULES_PENDING_MERGE - set(long)
    assert not stale, f"{sorted(stale)} are short now: remove them from KNOWN_LONG_MODULES_PENDING_MERGE"


def _long_functions(tree: ast.AST, prefix: str = "") -> dict[str, int]:
    out: dict[str, int] = {}
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            qual = f"{prefix}{node.name}"
            if not isinstance(node, ast.ClassDef):
                size = int(node.end_lineno or node.lineno) - node.lineno + 1
                if size > FUNCTION_LINES_MAX:
                    out[qual] = size
            out.update(_long_functions(node, qual + "."))
        else:
            out.update(_long_functions(node, prefix))
    return out


def test_long_function_check_sees_nested_and_methods() -> None:
    body = "\n".join(["    x = 1"] * (FUNCTION_LINES_MAX + 1))
    src = f"class A:\n    def m(self):\n    {body.replace(chr(10), chr(10) + '    ')}\ndef f():\n{body}\n"
    assert set(_long_functions(ast.parse(src))) == {"A.m", "f"}


def test_no_function_over_the_size_limit() -> None:
    long = {
        f"{name}:{qual}": size for name in _files() for qual, size in _long_functions(_tree(name)).items()
    }
    bad = {k: v for k, v in long.items() if k not in KNOWN_LONG_FUNCTIONS_PENDING_MERGE}
    assert not bad, f"functions over {FUNCTION_LINES_MAX} lines (split them into named steps): {bad}"
    stale = KNOWN_LONG_FUNCTIONS_PENDING_MERGE - set(long)
    assert not stale, f"{sorted(stale)} are short now: remove them from KNOWN_LONG_FUNCTIONS_PENDING_MERGE"

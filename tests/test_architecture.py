"""The package's shape: layers as folders, no import cycle, short functions.

The layer contract itself (which layer may import which) is import-linter's, in
pyproject.toml (``lint-imports``, run by CI).  These tests keep what it does not check.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys

import pytest

from tests.support.paths import ROOT

PACKAGE = ROOT / "wormgear_cli"

#: the modules allowed directly in wormgear_cli/ (everything else lives in a layer folder)
TOP_LEVEL = {"__init__.py", "__main__.py", "_docgen.py", "api.py", "angles.py", "errors.py", "files.py",
             "units.py"}

#: longest function, in lines (docstring included)
MAX_FUNCTION_LINES = 100

#: functions still longer than MAX_FUNCTION_LINES, to be split; this list only shrinks
KNOWN_LONG: set[str] = set()


def _modules() -> list[str]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out.append(".".join(parts))
    return out


def test_few_modules_sit_at_the_top():
    top = {p.name for p in PACKAGE.glob("*.py")}
    assert top <= TOP_LEVEL, f"modules outside a layer folder: {sorted(top - TOP_LEVEL)}"
    assert len(top) <= 8


def test_no_import_cycle():
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("wormgear_cli")  # imports inside functions included
    cycles = []
    for a in sorted(graph.modules):
        for b in graph.find_modules_directly_imported_by(a):
            if a.startswith(b + ".") or b.startswith(a + "."):
                continue  # a package and its own modules
            if graph.chain_exists(importer=b, imported=a):
                cycles.append(f"{a} -> {b} -> ... -> {a}")
    assert not cycles, "\n".join(cycles)


_FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef)
_IMPORTS = (ast.Import, ast.ImportFrom)


def _statements(body: list, in_function: bool = False):
    """(statement, whether it sits inside a function) for each statement of a block and of the blocks
    inside it.  Definitions and imports are statements, and statements sit only in these lists: the
    expressions (most of a syntax tree) need no walk."""
    for node in body:
        yield node, in_function
        inner = in_function or isinstance(node, _FUNCTIONS)
        for field in ("body", "orelse", "finalbody", "handlers", "cases"):
            block = getattr(node, field, None)
            if isinstance(block, list):
                yield from _statements(block, inner)


@functools.cache
def _function_facts() -> tuple[dict[str, int], dict[str, list[int]]]:
    """Every module of the package parsed once: (functions over MAX_FUNCTION_LINES: their lines, by
    ``path::name``; in-function imports without a reason: their line numbers, by path).  The syntax
    trees are not kept (a million objects every later garbage collection would walk)."""
    long: dict[str, int] = {}
    unexplained: dict[str, list[int]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text()
        rel = path.relative_to(ROOT).as_posix()
        imports = []
        for node, in_function in _statements(ast.parse(text).body):
            if isinstance(node, _FUNCTIONS):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long[f"{rel}::{node.name}"] = lines
            elif in_function and isinstance(node, _IMPORTS):
                imports.append(node)
        missing = _unexplained(text.splitlines(), sorted(imports, key=lambda n: n.lineno))
        if missing:
            unexplained[rel] = missing
    return long, unexplained


def _long_functions() -> dict[str, int]:
    return _function_facts()[0]


def test_no_new_long_function():
    long = _long_functions()
    new = {k: v for k, v in long.items() if k not in KNOWN_LONG}
    assert not new, f"functions over {MAX_FUNCTION_LINES} lines: {new}"


def test_known_long_functions_are_still_long():
    """A function split below the bar leaves KNOWN_LONG (the list only shrinks)."""
    long = _long_functions()
    assert not (KNOWN_LONG - set(long)), f"no longer long, remove from KNOWN_LONG: {sorted(KNOWN_LONG - set(long))}"


#: files whose in-function imports still wait for their reason (owned by a parallel change when this
#: check was written); this set only shrinks
IMPORT_REASON_PENDING: set[str] = set()


def _unexplained(lines: list[str], imports: list) -> list[int]:
    """Lines of the in-function imports (in line order) with no reason: a comment on the import's lines
    or on the line above; a run of imports on consecutive lines shares the comment above its first."""
    out: list[int] = []
    explained_ends: set[int] = set()
    for node in imports:
        own = any("#" in lines[i] for i in range(node.lineno - 1, node.end_lineno))
        above = node.lineno - 1
        if own or (above and lines[above - 1].strip().startswith("#")) or above in explained_ends:
            explained_ends.add(node.end_lineno)
        else:
            out.append(node.lineno)
    return out


def _unexplained_function_imports() -> dict[str, list[int]]:
    return _function_facts()[1]


def test_every_function_import_says_why():
    """Imports inside functions only where they buy start-up time or a layering need, each saying which."""
    missing = {k: v for k, v in _unexplained_function_imports().items() if k not in IMPORT_REASON_PENDING}
    assert not missing, f"in-function imports without a reason comment (file: lines): {missing}"


def test_pending_import_reasons_are_still_pending():
    """A file whose imports all say why leaves IMPORT_REASON_PENDING (the set only shrinks)."""
    done = IMPORT_REASON_PENDING - set(_unexplained_function_imports())
    assert not done, f"remove from IMPORT_REASON_PENDING: {sorted(done)}"


@pytest.mark.slow  # one fresh interpreter per module
def test_every_module_imports_on_its_own():
    failed = {}
    for mod in _modules():
        if mod.endswith("__main__"):
            continue  # runs the command line
        proc = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c", f"import {mod}"],
                              capture_output=True, text=True, cwd=ROOT)
        if proc.returncode:
            failed[mod] = proc.stderr.strip().splitlines()[-1]
    assert not failed, failed


#: modules mypy still checks with their errors ignored (pyproject's type-check debt); the number only
#: goes down: lower it when a module comes off the list
TYPE_DEBT_MODULES = 0


def test_the_type_check_debt_only_shrinks():
    import tomllib

    overrides = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]["overrides"]
    debt = [m for o in overrides if o.get("ignore_errors") for m in o["module"]]
    assert len(debt) <= TYPE_DEBT_MODULES, "a module joined the type-check debt: fix its types instead"
    assert len(debt) == len(set(debt))

"""bench/faults.py's hand-made faults still apply: each one's text occurs exactly once in its file
(a refactor that rewrites a line turns its fault into "moved", which mutation runs report but no
test noticed: three had moved unnoticed), and each names test paths that exist."""

from __future__ import annotations

import importlib.util

from tests.support.paths import ROOT


def _faults() -> dict:
    spec = importlib.util.spec_from_file_location("_bench_faults", ROOT / "bench" / "faults.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.FAULTS


def test_every_fault_applies_to_the_code_as_it_is():
    moved = {}
    for name, fault in _faults().items():
        text = (ROOT / "wormgear_cli" / fault.file).read_text(encoding="utf-8")
        if text.count(fault.old) != 1 or fault.old == fault.new:
            moved[name] = text.count(fault.old)
        missing = [t for t in fault.tests if not (ROOT / t.split("::")[0]).exists()]
        assert not missing, f"{name}: no such test path {missing}"
    assert moved == {}, f"faults whose text is not found exactly once (name: times found): {moved}"

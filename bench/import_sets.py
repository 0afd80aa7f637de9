"""Which modules each command loads: record them on two trees and compare.

Moving an import from inside a function to the top of its module costs nothing when every run
that loads the module loads the imported one anyway.  This script runs each case of
``bench/compare_outputs.py`` (``CASES``: every command on the shipped drives and field cases) plus
the bare imports ``wormgear_cli``, ``wormgear_cli.api`` and ``wormgear_cli.cli``, and stores the
names in ``sys.modules`` when each run ends; ``diff`` lists, per run, the modules one recording
loads and the other does not::

    python bench/import_sets.py record /tmp/before.json --tree /path/to/old/checkout
    python bench/import_sets.py record /tmp/after.json
    python bench/import_sets.py diff /tmp/before.json /tmp/after.json   # exit 1 on any difference

Runs use compare_outputs' environment and a scratch copy of ``configs/`` and the field cases.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from compare_outputs import CASES, ROOT, _env

#: runs ``args`` as ``wormgear`` would (or imports a module, for ``["@import", NAME]``) and writes the
#: names of the loaded modules, as JSON, to the file named first
PROBE = """
import atexit, json, runpy, sys
out, args = sys.argv[1], json.loads(sys.argv[2])
atexit.register(lambda: open(out, "w").write(json.dumps(sorted(sys.modules))))
if args[:1] == ["@import"]:
    __import__(args[1])
else:
    sys.argv = ["wormgear", *args]
    runpy.run_module("wormgear_cli", run_name="__main__", alter_sys=True)
"""

RUNS: dict[str, list[str]] = {**CASES, **{f"import-{m}": ["@import", m]
                                          for m in ("wormgear_cli", "wormgear_cli.api", "wormgear_cli.cli")}}


def record(out: Path, tree: Path) -> int:
    loaded = {}
    with tempfile.TemporaryDirectory(prefix="wormgear-imports-") as tmp:
        work = Path(tmp)
        shutil.copytree(tree / "configs", work / "configs")
        shutil.copytree(tree / "tests" / "data" / "field", work / "field")
        for name, args in RUNS.items():
            (work / "OUT").mkdir()
            names = work / "modules.json"
            subprocess.run([sys.executable, "-c", PROBE, str(names), json.dumps(args)], cwd=work, env=_env(tree),
                           capture_output=True, timeout=900)
            loaded[name] = json.loads(names.read_text())
            names.unlink()
            shutil.rmtree(work / "OUT")
            print(f"{name}: {len(loaded[name])} modules", file=sys.stderr)
    out.write_text(json.dumps(loaded, indent=0) + "\n")
    return 0


def diff(a: Path, b: Path) -> int:
    before, after = json.loads(a.read_text()), json.loads(b.read_text())
    bad = 0
    for name in sorted(set(before) | set(after)):
        x, y = set(before.get(name, ())), set(after.get(name, ()))
        if x != y:
            bad += 1
            print(f"{name}: + {sorted(y - x)}  - {sorted(x - y)}")
    print(f"{len(set(before) | set(after))} runs, {bad} with other modules")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("out", type=Path)
    r.add_argument("--tree", type=Path, default=ROOT)
    d = sub.add_parser("diff")
    d.add_argument("a", type=Path)
    d.add_argument("b", type=Path)
    args = ap.parse_args()
    return record(args.out, args.tree.resolve()) if args.cmd == "record" else diff(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())

"""The manifest of a part: what a ``--shard`` run with ``-o FILE`` wrote, and for which run.

``FILE.manifest.json`` is written beside the part, in the same output transaction, after it
(so a manifest never stands beside a half-written part).  It holds the command, the
program's version, the drive file's SHA-256, the run's parameters (every option that
changes the output's bytes; not ``--jobs``), the part (K, N, its first and stop item, the
total) and the part file's size and SHA-256.

A re-run of the same part finds the file complete when the manifest says the same command,
version, drive, parameters and part, and the file still has the recorded checksum; it then
skips the work (:func:`resume_note`).  ``wormgear merge`` reads the manifests to check that
the parts belong together (:func:`check_parts`).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from wormgear_cli.errors import UsageError

#: suffix of a part's manifest (``part3.csv`` -> ``part3.csv.manifest.json``)
SUFFIX = ".manifest.json"
#: the manifest layout's version (a field of every manifest)
LAYOUT = 1
#: largest manifest read [bytes] (a manifest is a few hundred bytes)
MAX_MANIFEST_BYTES = 1 << 20


def manifest_path(part: str | Path) -> Path:
    part = Path(part)
    return part.with_name(part.name + SUFFIX)


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file, read in 1 MiB pieces."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while piece := fh.read(1 << 20):
            h.update(piece)
    return h.hexdigest()


class Hashing:
    """Counts and hashes what is written through it: ``wrap(write)`` returns a write function
    that does both, so a streamed part is hashed without being read again."""

    def __init__(self):
        self.h, self.size = hashlib.sha256(), 0

    def add(self, data: str | bytes) -> bytes:
        raw = data.encode() if isinstance(data, str) else bytes(data)
        self.h.update(raw)
        self.size += len(raw)
        return raw

    def wrap(self, write):
        return lambda data: write(self.add(data))

    @property
    def file(self) -> dict:
        return {"bytes": self.size, "sha256": self.h.hexdigest()}


def run_key(command: str, version: str, drive_sha256: str, parameters: dict, part: dict) -> dict:
    """What identifies a part's run: the fields a re-run and ``merge`` compare."""
    return {"layout": LAYOUT, "command": command, "version": version, "drive_sha256": drive_sha256,
            "parameters": parameters, "part": part}


def document(key: dict, drive_path: str | Path, file_info: dict, name: str) -> str:
    """The manifest's JSON text: ``key`` (:func:`run_key`), the drive's path (absolute, for
    ``merge``) and the part file's name, size and checksum."""
    doc = {**key, "drive": str(Path(drive_path).resolve()), "file": {"name": name, **file_info}}
    return json.dumps(doc, indent=2, sort_keys=True) + "\n"


def read(path: str | Path) -> dict | None:
    """The manifest beside part ``path`` (None when there is none or it is not a manifest)."""
    m = manifest_path(path)
    try:
        if not m.is_file() or m.stat().st_size > MAX_MANIFEST_BYTES:
            return None
        doc = json.loads(m.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return doc if isinstance(doc, dict) and doc.get("layout") == LAYOUT else None


def _key_of(doc: dict) -> dict:
    return {k: doc.get(k) for k in ("layout", "command", "version", "drive_sha256", "parameters", "part")}


def resume_note(path: str | Path, key: dict) -> str | None:
    """Why part ``path`` need not be computed again (a sentence for stderr), or None when it must:
    no file or manifest, a manifest of another run, or a file changed since it was written."""
    path = Path(path)
    doc = read(path)
    if doc is None or not path.is_file() or _key_of(doc) != key:
        return None
    info = doc.get("file") or {}
    try:
        if path.stat().st_size != info.get("bytes") or file_sha256(path) != info.get("sha256"):
            return None
    except OSError:
        return None
    return f"{path} is complete and its manifest matches this run; skipped (delete it to compute it again)"


def _difference(a: dict, b: dict) -> str:
    """The first field in which two run keys differ, as words: "seed 1 vs 0" (b's value first)."""
    for field in ("command", "version", "drive_sha256"):
        if a.get(field) != b.get(field):
            what = {"command": "command", "version": "wormgear version", "drive_sha256": "drive file"}[field]
            return f"{what} {b.get(field)} vs {a.get(field)}" if field != "drive_sha256" else \
                "another drive file (its SHA-256 differs)"
    pa, pb = a.get("parameters") or {}, b.get("parameters") or {}
    for name in sorted(set(pa) | set(pb)):
        if pa.get(name) != pb.get(name):
            return f"{name} {pb.get(name)!r} vs {pa.get(name)!r}"
    qa, qb = a.get("part") or {}, b.get("part") or {}
    if qa.get("n") != qb.get("n"):
        return f"number of parts {qb.get('n')} vs {qa.get('n')}"
    return "another run"


def check_parts(paths: list) -> tuple[list[dict], list[str]]:
    """The manifests of ``paths`` in part order, and the problems (one line each): a part without
    a manifest, changed since it was written, of another run than the first, given twice, or
    missing.  Reads every file once (its checksum)."""
    problems, found = [], []
    for p in paths:
        p = Path(p)
        if not p.is_file():
            problems.append(f"{p}: file not found, expected a part written by --shard K/N -o FILE")
            continue
        doc = read(p)
        if doc is None:
            problems.append(f"{p}: no manifest ({manifest_path(p).name}); only parts written with --shard and -o "
                            "can be merged (an interrupted part has none: run it again)")
            continue
        info = doc.get("file") or {}
        if p.stat().st_size != info.get("bytes") or file_sha256(p) != info.get("sha256"):
            problems.append(f"{p}: changed since it was written (its checksum differs from its manifest); run "
                            "the part again")
            continue
        found.append((p, doc))
    if not found:
        return [], problems or ["no part to merge"]
    first_path, first = found[0]
    by_k: dict = {}
    claimed: dict = {}  # part number -> the files of another run that claimed it
    for p, doc in found:
        key, ref = _key_of(doc), _key_of(first)
        if {**key, "part": None} != {**ref, "part": None} or (key["part"] or {}).get("n") != ref["part"].get("n"):
            problems.append(f"{p}: not a part of the run of {first_path} ({_difference(ref, key)}); merge parts "
                            "of one run only")
            claimed.setdefault((key["part"] or {}).get("k"), []).append(p)
            continue
        by_k.setdefault(doc["part"]["k"], []).append(p)
    n = int(first["part"]["n"])
    for k in sorted(by_k):
        if len(by_k[k]) > 1:
            problems.append(f"part {k}/{n} given twice ({', '.join(map(str, by_k[k]))})")
    missing = [k for k in range(1, n + 1) if k not in by_k]
    for k in missing:
        given = f" (given only from another run: {', '.join(map(str, claimed[k]))})" if k in claimed else ""
        problems.append(f"part {k}/{n} missing{given} (run it with --shard {k}/{n})")
    ordered = [dict(doc, path=str(p)) for k in sorted(by_k) for p, doc in found if p == by_k[k][0]]
    return ordered, problems


def require_parts(paths: list) -> list[dict]:
    """:func:`check_parts`, raising :class:`UsageError` with every problem (one line each)."""
    parts, problems = check_parts(paths)
    if problems:
        raise UsageError(problems)
    return parts

"""``wormgear merge``: the parts of a sharded run joined into the unsharded run's output.

The parts are checked through their manifests (:mod:`wormgear_cli.batch.manifest`): every
part of one run, each once, none changed since it was written.  Then:

* ``sweep`` (CSV parts): the header once, then every part's rows in order -- the unsharded
  CSV byte for byte.
* ``tolerance`` (CSV or NPY parts): the samples are read back part after part, joined at the
  random-stream block boundaries (:func:`~wormgear_cli.tolerance.engine.rebatch`) and
  summarized as the unsharded run summarizes them, so the report (table or JSON) is the
  unsharded run's byte for byte; ``--format csv`` gives the unsharded samples CSV.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

from wormgear_cli.batch import manifest
from wormgear_cli.errors import UsageError

#: the formats of mergeable parts, per command
MERGEABLE = {"sweep": ("csv",), "tolerance": ("csv", "npy")}
#: bytes copied at a time when joining CSV parts
_COPY = 1 << 20


def parts_of(paths: list) -> list[dict]:
    """The parts' manifests in part order (UsageError with one line per problem: missing,
    duplicate, changed or mismatched parts, or parts in a format that cannot be merged)."""
    parts = manifest.require_parts(paths)
    command, fmt = parts[0]["command"], parts[0]["parameters"].get("format")
    if fmt not in MERGEABLE.get(command, ()):
        raise UsageError(f"{parts[0]['path']}: {command} parts in {fmt} cannot be merged; run the parts with "
                         f"--format {' or '.join(MERGEABLE.get(command, ('csv',)))}")
    return parts


def joined_csv(parts: list[dict]) -> Iterator[bytes]:
    """The CSV parts joined: the first part whole, then every other part without its header line."""
    for n, part in enumerate(parts):
        with open(part["path"], "rb") as fh:
            if n:
                fh.readline()
            while piece := fh.read(_COPY):
                yield piece


def check_drive(drive: Path, parts: list[dict]) -> None:
    """UsageError unless ``drive`` is the file the parts were computed with (same SHA-256)."""
    if not Path(drive).is_file():
        raise UsageError(f"{drive}: file not found (the drive the parts were computed with); give it with --drive")
    if manifest.file_sha256(drive) != parts[0]["drive_sha256"]:
        raise UsageError(f"{drive}: not the drive the parts were computed with (its SHA-256 differs from their "
                         "manifests'); give that file with --drive")


def tolerance_setup(spec, parts: list[dict], jobs: int = 1):
    """The unsharded run's :class:`~wormgear_cli.tolerance.engine.Setup`, from the parts' parameters."""
    # lazy: tolerance.engine pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.tolerance import engine

    p = parts[0]["parameters"]
    options = engine.Options(samples=p["samples"], seed=p["seed"], metrics=p["metrics"], plan=p["plan"],
                             targets=p["targets"], points=p["points"], unit=p["unit"], jobs=jobs)
    return engine.setup(spec, options)


def tolerance_blocks(s, parts: list[dict]) -> Iterator:
    """The samples of the parts as the unsharded run's blocks (same boundaries, same values)."""
    # lazy: tolerance.engine pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.tolerance import engine, report

    def each():
        for part in parts:
            sp = replace(s, start=part["part"]["first"], stop=part["part"]["stop"])
            path = Path(part["path"])
            yield from (report.read_npy(path, sp) if part["parameters"]["format"] == "npy"
                        else report.read_samples(path, sp))

    return engine.rebatch(each())


def tolerance_summary(s, parts: list[dict]):
    """The unsharded run's :class:`~wormgear_cli.tolerance.engine.Summary` from the parts."""
    # lazy: tolerance.engine pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.tolerance import engine

    return engine.summarize(s, lambda: tolerance_blocks(s, parts))

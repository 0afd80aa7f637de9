"""Writers of files other programs load, as a registry: format name -> :class:`Writer`.

Each writer lives in its own module of this package and provides ``write(result, options)``
(the file's text) and, optionally, ``instructions(options)`` (how to load the file, one line
each).  A writer says what it ``accepts`` (the kind of result it writes), the file name
endings it owns (so ``-o table.comp`` can stand for ``--format linuxcnc``), and, for tables, how
many points the target program takes.  Adding a format means one line in :data:`WRITERS` and
one module.  The modules are imported only when used.

Kinds accepted so far: ``"correction table"``
(:class:`~wormgear_cli.compensation.table.CorrectionTable`) and ``"pec curve"``
(:class:`~wormgear_cli.compensation.pec.PecCurve`).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from wormgear_cli.errors import UsageError, did_you_mean

#: what :data:`WRITERS` accept
CORRECTION_TABLE = "correction table"
PEC_CURVE = "pec curve"


@dataclass(frozen=True)
class WriteOptions:
    """What a writer may need besides the result.

    ``unit``: angle unit of the values where the format leaves it free
    (CSV); ``file_type``: LinuxCNC ``COMP_FILE_TYPE`` (0 or 1);
    ``steps_per_worm``: the mount's motor steps per worm turn (EQMOD), or
    None; ``caption``: a one-line description for formats with a comment
    line; ``path``: the file's name as it will be loaded (for the loading
    instructions), or None for stdout.
    """

    unit: str = "arcsec"
    file_type: int = 1
    steps_per_worm: int | None = None
    caption: str = ""
    path: str | None = None


@dataclass(frozen=True)
class Writer:
    """One output format: ``name`` (the ``--format`` value), ``accepts`` (the kind of result),
    ``extensions`` (file name endings, lower case, with the dot), ``module`` (under
    ``wormgear_cli.output.writers``), ``summary`` (one line for help and docs),
    ``max_points`` and ``default_points`` (table formats: the most points the target program
    takes, and the default; None when it does not apply)."""

    name: str
    accepts: str
    extensions: tuple[str, ...]
    module: str
    summary: str
    max_points: int | None = None
    default_points: int | None = None

    def _module(self):
        return importlib.import_module(f"{__name__}.{self.module}")

    def write(self, result, options: WriteOptions | None = None) -> str:
        """The file's text."""
        return self._module().write(result, options or WriteOptions())

    def instructions(self, options: WriteOptions | None = None) -> list[str]:
        """How to load the file (lines for stderr and the docs); empty when the format has none."""
        fn = getattr(self._module(), "instructions", None)
        return list(fn(options or WriteOptions())) if fn else []


#: the registry: format name -> writer
WRITERS: dict[str, Writer] = {w.name: w for w in (
    Writer("linuxcnc", CORRECTION_TABLE, (".comp", ".tbl"), "linuxcnc",
           "LinuxCNC joint compensation file (COMP_FILE), type 1 or 0", max_points=256, default_points=256),
    Writer("eqmod", PEC_CURVE, (".pec",), "eqmod", "EQMOD / EQASCOM periodic error correction file"),
    Writer("csv", CORRECTION_TABLE, (".csv",), "correction_csv",
           "angle, correction forward, correction reverse, in --unit (any other controller)", default_points=361),
)}


def names(accepts: str | None = None) -> tuple[str, ...]:
    """The registered format names (those accepting ``accepts`` when given)."""
    return tuple(n for n, w in WRITERS.items() if accepts is None or w.accepts == accepts)


def get(name: str, option: str = "--format") -> Writer:
    """The writer called ``name``; UsageError naming the known ones otherwise."""
    try:
        return WRITERS[name]
    except KeyError:
        hint = did_you_mean(name, WRITERS)
        raise UsageError(f"{option}: unknown format {name!r}{hint}; expected one of {', '.join(WRITERS)}") from None


def for_path(path: str | Path | None, accepts: str | None = None) -> Writer | None:
    """The writer owning the file name ending of ``path`` (case-insensitive), or None."""
    if path is None:
        return None
    name = Path(str(path)).name.lower()
    for w in WRITERS.values():
        if (accepts is None or w.accepts == accepts) and any(name.endswith(e) for e in w.extensions):
            return w
    return None


def extensions() -> dict[str, str]:
    """File name ending -> format name, over every writer (for ``-o`` format inference)."""
    return {e: w.name for w in WRITERS.values() for e in w.extensions}

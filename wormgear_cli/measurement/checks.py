"""Checks on what a measurement file does not state: repeated targets without a direction
column, duplicate rows, time going backwards, one direction or one target only.

Each finding is a :class:`Finding`; ``measure`` and ``diagnose`` both read
:func:`structure_findings`, the one definition.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wormgear_cli.physics.signals import CONDITIONS


@dataclass(frozen=True)
class Finding:
    """One thing the checks found: ``kind`` (a short key), ``text`` (a sentence with the likely fix),
    ``warning`` (True: something looks wrong; False: information), ``verdict`` (shown in the verdict line)."""

    kind: str
    text: str
    warning: bool
    verdict: str | None = None


#: rows hashed or compared at a time by :func:`duplicate_rows` (its temporaries stay small)
BLOCK = 1 << 16


def duplicate_rows(m, repeated=None) -> int:
    """Number of rows that repeat an earlier row exactly (every canonical value equal).

    Rows are sorted by a 64-bit mix of their values (one sort), and rows with
    equal keys compared value by value.  ``repeated`` (bool per row): the
    rows whose angle occurs more than once, the only ones that can be
    duplicates (a dense scan then needs no sort).  No column is copied: the
    keys are mixed and the candidates compared a block of rows at a time."""
    cols = [m.angle, m.error, m.direction, m.run] + [
        getattr(m, s.name) for s in CONDITIONS if s.column in m.present]
    n = len(m)
    if n < 2:
        return 0
    sel = None if repeated is None else np.flatnonzero(repeated)
    if sel is not None and sel.size < 2:
        return 0
    size = n if sel is None else sel.shape[0]
    key = np.empty(size, dtype=np.uint64)
    for a in range(0, size, BLOCK):
        rows = slice(a, a + BLOCK) if sel is None else sel[a:a + BLOCK]
        part = np.zeros(key[a:a + BLOCK].shape[0], dtype=np.uint64)
        with np.errstate(over="ignore"):
            for i, c in enumerate(cols):
                part ^= np.ascontiguousarray(c[rows], dtype=float).view(np.uint64)
                part *= np.uint64(0x9E3779B97F4A7C15 + 2 * i)
        key[a:a + BLOCK] = part
    order = np.argsort(key, kind="stable")
    key = key[order]  # sorted
    same = 0
    for a in range(0, size - 1, BLOCK):
        b = min(a + BLOCK, size - 1)
        cand = np.flatnonzero(key[a + 1:b + 1] == key[a:b]) + a
        if cand.size == 0:
            continue
        first, second = order[cand], order[cand + 1]
        if sel is not None:
            first, second = sel[first], sel[second]
        equal = np.ones(cand.size, dtype=bool)
        for c in cols:
            equal &= c[first] == c[second]
        same += int(np.count_nonzero(equal))
    return same


def guide_log_findings(m) -> list:
    """The findings of a guide log: the reader's notes and warnings (pulse sign, lock changes); the
    checks of targets and directions do not apply (every frame is at its own angle, one way)."""
    return ([Finding("reader", note, False) for note in m.notes]
            + [Finding("guide_log", w, True, "see warnings") for w in m.warnings])


def structure_findings(m, target_index: np.ndarray, repeated=None) -> tuple[list, bool]:
    """Findings about what the file does not state, and whether the directions are mixed.

    Parameters
    ----------
    m : Measurement
    target_index : ndarray of int, shape (n,)
        Target of each row (:func:`~wormgear_cli.measurement.iso230.group_targets`).
    repeated : ndarray of bool, shape (n,), optional
        Rows whose angle occurs more than once (see :func:`duplicate_rows`).
    """
    out = []
    n = len(m)
    for note in m.notes:
        if note.startswith("no run column: time_s goes backwards"):
            verdict = "passes inferred from time restarts"
        elif "with every cell empty left out" in note:  # said in the verdict line, not only in a note
            verdict = note.split(" (", 1)[0]
        else:
            verdict = None
        out.append(Finding("reader", note, False, verdict))
    for w in m.warnings:
        out.append(Finding("units", w, True, "check the units (see warnings)"))
    mixed = False
    if "direction" not in m.present:
        key = m.run.astype(np.int64) * (int(target_index.max()) + 1) + target_index.astype(np.int64)
        if np.unique(key).shape[0] != n:
            # forward and reverse visits cannot be told apart: the one-direction figures would mix them
            mixed = True
            read = {cell for _, cell in m.columns}
            unread = [h for h in m.header if h and h not in read]
            hint = (f"; columns not read: {', '.join(unread)} (map one with --map direction=HEADER or "
                    "--map run=HEADER)") if unread else ""
            if "run" not in m.present:
                out.append(Finding(
                    "repeated_targets",
                    "no direction or run column: every row is taken as forward, yet the rows visit the same target "
                    "more than once, so forward and reverse visits cannot be told apart: add a direction column "
                    "(+1 forward, -1 reverse) or, for repeated one-direction runs, a run column; the one-direction "
                    f"figures (s, R, A, E) are withheld{hint}", True,
                    "targets repeat without direction or run column: one-direction figures withheld"))
            else:
                out.append(Finding(
                    "mixed_directions",
                    "no direction column: every row is taken as forward, yet one run visits the same target more "
                    "than once: if some visits were made in reverse, add a direction column (+1 forward, -1 "
                    f"reverse); the one-direction figures (s, R, A, E) are withheld{hint}",
                    True, "targets repeat within a run without a direction column: one-direction figures withheld"))
    dups = duplicate_rows(m, repeated)
    if dups:
        rows = 's are exact duplicates' if dups > 1 else ' is an exact duplicate'
        out.append(Finding("duplicates", f"{dups} row{rows}"
                           " of another row (pasted twice?): they count twice in every figure; remove them if they "
                           "are copies", True, f"{dups} duplicate row{'s' if dups > 1 else ''}"))
    if "time_s" in m.present and "run" not in m.derived:
        back = (np.diff(m.time) < 0) & (m.run[1:] == m.run[:-1])
        nb = int(np.count_nonzero(back))
        if nb:
            out.append(Finding("time_order", f"time_s goes backwards {nb} time{'s' if nb > 1 else ''} inside a run "
                               "(rows out of order, or runs joined without a run number)", True,
                               "time not monotonic inside a run"))
    has_up, has_dn = bool(np.any(m.direction > 0)), bool(np.any(m.direction < 0))
    if not (has_up and has_dn) and not mixed:
        which = "forward" if has_up else "reverse"
        out.append(Finding("one_direction", "", False, f"one direction only ({which})"))
    if int(target_index.max()) == 0:
        out.append(Finding("one_target", "", False, "one target (one-position test): A, E, M and orders n/a"))
    return out, mixed

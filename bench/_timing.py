"""Timing helper shared by the bench scripts (run them as `python bench/NAME.py`)."""

from __future__ import annotations

import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def best_of(fn, repeat: int = 3) -> float:
    """Shortest wall time [s] of ``repeat`` calls of ``fn`` (the least disturbed run)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


@contextmanager
def checkout(rev: str | None, where: Path) -> Iterator[Path | None]:
    """A checkout of git revision ``rev`` at ``where`` for the block (``git worktree add``, removed
    after it); None without ``rev``: the "before" tree of a before/after bench."""
    if rev is None:
        yield None
        return
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), rev], check=True,
                   capture_output=True)
    try:
        yield where
    finally:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(where)], capture_output=True)

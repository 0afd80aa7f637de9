"""Timing helper shared by the bench scripts (run them as `python bench/NAME.py`)."""

from __future__ import annotations

import time


def best_of(fn, repeat: int = 3) -> float:
    """Shortest wall time [s] of ``repeat`` calls of ``fn`` (the least disturbed run)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)

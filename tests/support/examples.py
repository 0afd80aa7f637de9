"""How many examples a costly property test draws (issue 26: the everyday run under a minute of CPU).

Its full count in CI and in any run that selects slow tests (``-m 'slow or not slow'``, ``-m slow``);
a quarter of it, at least 5, in the everyday run (pyproject's ``-m 'not slow'``).  CI also gets the
full count through the environment: ``CI`` set, or ``WORMGEAR_TEST_EXAMPLES=full`` (which ``.ci/run``
and ``bench/mutation.py`` set).  ``tests/conftest.py`` sets :data:`FULL` before any test module is
imported, so ``@settings(max_examples=examples(40))`` reads it when the module is collected."""

from __future__ import annotations

#: whether property tests draw their full count (see the module's docstring)
FULL = True


def examples(n: int) -> int:
    """``n`` in a full run, else ``max(5, n // 4)``."""
    return n if FULL else max(5, n // 4)

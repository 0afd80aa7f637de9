"""The ``wormgear`` command line: a thin typer layer over the core.

Each command lives in its own module and registers itself on :data:`app`;
heavy modules (numpy models, rich, matplotlib) are imported inside the
command functions so start-up stays fast.
"""

from __future__ import annotations

from wormgear_cli.cli.app import app
from wormgear_cli.cli import analyze  # noqa: F401  (analyze, check, new)
from wormgear_cli.cli import sweep  # noqa: F401
from wormgear_cli.cli import simulate  # noqa: F401  (simulate, synth)
from wormgear_cli.cli import measure  # noqa: F401
from wormgear_cli.cli import diagnose  # noqa: F401


def main() -> None:
    app(prog_name="wormgear")


__all__ = ["app", "main"]

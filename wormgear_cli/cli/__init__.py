"""The ``wormgear`` command line: a thin typer layer over the core.

Each command lives in its own module and registers itself on :data:`app`;
heavy modules (numpy models, rich, matplotlib) are imported inside the
command functions so start-up stays fast.
"""

from __future__ import annotations

from wormgear_cli.cli.app import app
from wormgear_cli.cli import analyze  # noqa: F401  (registers analyze, check, new)


def main() -> None:
    app(prog_name="wormgear")


__all__ = ["app", "main"]

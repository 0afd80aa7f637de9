"""The ``wormgear`` command line: a thin typer layer over the core.

Each command lives in its own module and registers itself on :data:`app`.
Start-up is kept fast in two ways: heavy modules (numpy models, rich,
matplotlib) are imported inside the command functions, and :func:`main`
builds only the command being run (typer otherwise inspects every
command's signature on each start; the "lazy subcommand" pattern).
"""

from __future__ import annotations

import sys

from wormgear_cli.cli.app import app, single_command_app
from wormgear_cli.cli import analyze  # noqa: F401  (analyze, check, new)
from wormgear_cli.cli import sweep  # noqa: F401
from wormgear_cli.cli import simulate  # noqa: F401  (simulate, synth)
from wormgear_cli.cli import measure  # noqa: F401
from wormgear_cli.cli import diagnose  # noqa: F401
from wormgear_cli.cli import tolerance  # noqa: F401
from wormgear_cli.cli import grade  # noqa: F401


def main() -> None:
    args = sys.argv[1:]
    single = single_command_app(args[0]) if args and not args[0].startswith("-") else None
    (single or app)(prog_name="wormgear")


__all__ = ["app", "main"]

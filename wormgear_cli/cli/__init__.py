"""The ``wormgear`` command line: a thin typer layer over the core.

Each command lives in its own module and registers itself on :data:`app`.
Start-up is kept fast in three ways: heavy modules (numpy models, rich,
matplotlib) are imported inside the command functions; :func:`main` imports
only the module of the command being run; and it builds only that command
(typer otherwise inspects every command's signature on each start; the "lazy
subcommand" pattern).  ``from wormgear_cli.cli import app`` gives the full app,
every command registered.
"""

from __future__ import annotations

import importlib
import sys

#: command name -> module registering it (the one table of commands)
COMMAND_MODULES = {
    "analyze": "analyze", "check": "analyze", "new": "analyze",
    "sweep": "sweep",
    "simulate": "simulate", "synth": "simulate",
    "measure": "measure",
    "diagnose": "diagnose",
    "tolerance": "tolerance",
    "grade": "grade",
    "merge": "merge",
    "compensate": "compensate",
}


def _register(modules) -> None:
    for module in dict.fromkeys(modules):
        importlib.import_module(f"wormgear_cli.cli.{module}")


def __getattr__(name: str):
    if name == "app":  # the full app: every command registered
        _register(COMMAND_MODULES.values())
        from wormgear_cli.cli._app import app

        return app
    raise AttributeError(name)


def main() -> None:
    from wormgear_cli.cli._app import single_command_app

    args = sys.argv[1:]
    name = args[0] if args and not args[0].startswith("-") else None
    if name in COMMAND_MODULES:
        _register([COMMAND_MODULES[name]])
        single = single_command_app(name)
    else:
        single = None
    (single or __getattr__("app"))(prog_name="wormgear")


__all__ = ["app", "main", "COMMAND_MODULES"]

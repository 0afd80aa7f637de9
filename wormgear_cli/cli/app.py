"""The typer application object and its error boundary.

Core code raises :class:`~wormgear_cli.errors.WormgearError`; only here is
it turned into one stderr line per problem and the exit code 2.
"""

from __future__ import annotations

import typer
from typer.core import TyperGroup

from wormgear_cli.errors import WormgearError


class WormgearGroup(TyperGroup):
    """Runs a command; a user mistake becomes messages + exit code, never a traceback."""

    def invoke(self, ctx):
        from wormgear_cli.io import output_transaction

        try:
            # every file a command writes is committed together at its end: a failed
            # run (user error, bug, Ctrl-C) leaves no output; a clean exit (also
            # exit code 1 of a failed check) writes them
            with output_transaction() as tx:
                try:
                    return super().invoke(ctx)
                except typer.Exit:
                    tx.commit()
                    raise
        except WormgearError as exc:
            for line in exc.problems:
                typer.echo(f"error: {line}", err=True)
            raise typer.Exit(exc.exit_code) from None
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            raise typer.Exit(130) from None


SETTINGS = dict(
    name="wormgear",
    cls=WormgearGroup,
    help="Transmission error and backlash of two-stage worm + spur gear precision drives.\n\n"
    "Example: wormgear analyze configs/mch50.toml --unit arcsec",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)

app = typer.Typer(**SETTINGS)


def _version(value: bool) -> None:
    if value:
        from wormgear_cli import __version__

        typer.echo(f"wormgear {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(False, "--version", help="Print the version and exit.", callback=_version,
                                 is_eager=True),
) -> None:
    """Transmission error and backlash of two-stage worm + spur gear precision drives."""


def single_command_app(name: str):
    """An app holding only command ``name`` (registered on :data:`app`), or None if
    there is no such command.  typer then builds one command instead of all of
    them; that command behaves exactly as in the full app.  Used by ``main``."""
    infos = [c for c in app.registered_commands
             if (c.name or c.callback.__name__.replace("_", "-")) == name]
    if not infos:
        return None
    single = typer.Typer(**SETTINGS)
    single.registered_commands = infos

    @single.callback()
    def _group() -> None:  # a callback keeps it a group: "wormgear NAME ..." as with the full app
        pass

    return single

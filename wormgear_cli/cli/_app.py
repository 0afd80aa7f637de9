"""The typer application object and its error boundary.

Core code raises :class:`~wormgear_cli.errors.WormgearError`; only here is
it turned into one stderr line per problem and the exit code 2.
"""

from __future__ import annotations

import errno
import signal

import typer
from typer._click.exceptions import NoArgsIsHelpError, UsageError
from typer.core import TyperGroup

from wormgear_cli import __version__
from wormgear_cli.errors import UsageError as CoreUsageError
from wormgear_cli.errors import WormgearError, escape
from wormgear_cli.files import (
    BROKEN_PIPE_EXIT,
    OUT_OF_MEMORY,
    RunStopped,  # re-exported: the class lives with the signal handlers
    StdoutClosed,
    _stdout_failed,
    flush_stdout,
    install_stop_handlers,
    output_transaction,
    settle,
)


def _say(line: str) -> None:
    """One line on stderr; a stderr that is gone (the terminal closed: SIGHUP) is not an error
    of its own, the exit code still tells."""
    try:
        typer.echo(escape(line), err=True)
    except (OSError, ValueError):
        pass


def _signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def _usage_error_exit(exc) -> typer.Exit:
    """A command-line mistake (unknown option, bad choice, missing argument) as the project's one
    ``error:`` line with where to look, exit 2 -- not click's usage block of three lines."""
    ctx = getattr(exc, "ctx", None)
    where = ctx.command_path if ctx is not None else "wormgear"
    message = " ".join(exc.format_message().split()).rstrip(".")
    _say(f"error: {message}; see '{where} --help'")
    return typer.Exit(2)


class WormgearGroup(TyperGroup):
    """Runs a command; a user mistake becomes messages + exit code, never a traceback.

    Exit codes: 0 ok, 1 a check ran and failed, 2 bad usage/input or an output that
    cannot be written, 128 + N stopped by signal N (130 Ctrl-C, 129 SIGHUP, 143
    SIGTERM; a stdout closed by its reader ends quietly with 0).  A stopped run leaves no output file.
    """

    def make_context(self, info_name, args, parent=None, **extra):
        try:
            return super().make_context(info_name, args, parent=parent, **extra)
        except NoArgsIsHelpError:
            raise
        except UsageError as exc:  # an option of the program itself (wormgear --bogus)
            raise _usage_error_exit(exc) from None
        except KeyboardInterrupt:  # Ctrl-C while the options are read: nothing was written
            raise _stopped_exit(2) from None
        except RunStopped as exc:
            raise _stopped_exit(exc.signum) from None

    def invoke(self, ctx):
        restore = install_stop_handlers()
        tx = None
        out_of_memory = False
        try:
            # every file a command writes is committed together at its end: a failed
            # run (user error, bug, Ctrl-C, SIGTERM, SIGHUP, closed stdout) leaves no
            # output; a clean exit (also exit code 1 of a failed check) writes them
            with output_transaction() as tx:
                try:
                    result = super().invoke(ctx)
                    flush_stdout()
                    return result
                except typer.Exit as stop:
                    flush_stdout()
                    if stop.exit_code in (0, 1):  # done, or a check that ran and failed: its report stands
                        tx.commit(stop.exit_code)
                    raise  # exit 2 (bad input): no output file, as for an error raised
        except WormgearError as exc:
            for line in exc.in_flags(_flags(ctx)) if isinstance(exc, CoreUsageError) else exc.problems:
                _say(f"error: {line}")
            raise typer.Exit(exc.exit_code) from None
        except NoArgsIsHelpError:
            raise
        except UsageError as exc:
            raise _usage_error_exit(exc) from None
        except StdoutClosed:
            raise typer.Exit(BROKEN_PIPE_EXIT) from None
        except (KeyboardInterrupt, RunStopped) as exc:
            if tx is not None and tx.done is not None:  # after the commit: the outputs stand
                raise typer.Exit(tx.done) from None
            raise _stopped_exit(getattr(exc, "signum", 2)) from None
        except MemoryError:
            out_of_memory = True  # said below, once this frame's arrays are released
        except OSError as exc:  # stdout written outside write_stdout (help text, a terminal)
            code = _output_error_exit(exc)
            if code is None:
                raise
            raise typer.Exit(code) from None
        finally:
            restore()
        if out_of_memory:
            _say(f"error: {OUT_OF_MEMORY}")
            raise typer.Exit(2)

    def main(self, *args, **kwargs):
        try:
            return super().main(*args, **kwargs)
        except OSError as exc:  # --help / --version text to a full or closed stdout
            code = _output_error_exit(exc)
            if code is None:
                raise
            raise SystemExit(code) from None


def _flags(ctx) -> dict[str, str]:
    """The running command's flags by parameter name (``max_effects`` -> ``--max-effects``): what the
    core's messages name in the API's words (:meth:`wormgear_cli.errors.UsageError.in_flags`)."""
    name = ctx.invoked_subcommand
    command = ctx.command.get_command(ctx, name) if name else None
    if command is None:
        return {}
    return {p.name: max(p.opts, key=len) for p in command.params if p.name and p.opts and p.opts[0].startswith("-")}


def _stopped_exit(signum: int) -> typer.Exit:
    """Ctrl-C (SIGINT), SIGTERM or SIGHUP stopped the run before its outputs were committed:
    one line, exit 128 + N; a further signal while it exits ends the process at once."""
    code = 128 + signum
    settle(code)
    if signum == 2:
        _say("interrupted; no output written")
    else:
        _say(f"stopped by {_signal_name(signum)}; no output written")
    return typer.Exit(code)


def _output_error_exit(exc: OSError):
    """Exit code for a failed write to stdout (after one stderr line), None if ``exc`` is
    not an output error."""
    if exc.errno not in (errno.EPIPE, errno.ENOSPC, errno.EIO, errno.EFBIG, errno.EBADF,
                         getattr(errno, "EDQUOT", -1)):
        return None
    try:
        _stdout_failed(exc)
    except StdoutClosed:
        return BROKEN_PIPE_EXIT
    except CoreUsageError as err:
        for line in err.problems:
            _say(f"error: {line}")
        return err.exit_code
    return None


def _typer() -> typer.Typer:
    """The application's settings on a new (empty) typer app."""
    return typer.Typer(
        name="wormgear",
        cls=WormgearGroup,
        help="Transmission error and backlash of precision drives: worm, spur and belt stages in series.\n\n"
             "Example: wormgear analyze configs/mch50.toml --unit arcsec",
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )


app = _typer()


def _version(value: bool) -> None:
    if value:
        typer.echo(f"wormgear {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(False, "--version", help="Print the version and exit.", callback=_version,
                                 is_eager=True),
) -> None:
    """Transmission error and backlash of precision drives: worm, spur and belt stages in series."""


def single_command_app(name: str):
    """An app holding only command ``name`` (registered on :data:`app`), or None if
    there is no such command.  typer then builds one command instead of all of
    them; that command behaves exactly as in the full app.  Used by ``main``."""
    infos = [c for c in app.registered_commands
             if (c.name or getattr(c.callback, "__name__", "").replace("_", "-")) == name]
    if not infos:
        return None
    single = _typer()
    single.registered_commands = infos

    @single.callback()
    def _group() -> None:  # a callback keeps it a group: "wormgear NAME ..." as with the full app
        pass

    return single

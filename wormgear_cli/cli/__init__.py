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

import atexit
import gc
import importlib
import os
import signal
import sys

#: command name -> module registering it (the one table of commands)
COMMAND_MODULES = {
    "analyze": "analyze", "check": "analyze", "new": "analyze", "upgrade": "analyze",
    "sweep": "sweep",
    "simulate": "simulate", "synth": "simulate",
    "measure": "measure",
    "diagnose": "diagnose",
    "tolerance": "tolerance",
    "grade": "grade",
    "merge": "merge",
    "compare": "compare",
    "compensate": "compensate",
}


#: the thread-count variables of the BLAS libraries numpy may be built with (OpenBLAS reads the first
#: three, MKL, BLIS and Accelerate their own)
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")


def one_blas_thread(environ) -> bool:
    """Run numpy's BLAS on one thread unless the user chose a thread count: when none of
    :data:`BLAS_THREAD_VARIABLES` is set in ``environ`` (a mutable mapping, e.g. ``os.environ``),
    set them all to 1 and return True.  Must run before numpy is imported to take effect.

    Why: the commands' matrices are small (a diagnose fit is 2305 x 90), so a second BLAS
    thread only spins: measured on the 19-session EQ6 guide log, ``diagnose`` took 185 s of
    CPU with OpenBLAS's default threads against 17 s on one (bench/bench_cases.py
    --env default), and the threaded sums, split differently, changed the report in the 5th digit:
    one thread makes the result the same whatever the machine's core count."""
    if any(environ.get(name) for name in BLAS_THREAD_VARIABLES):
        return False
    for name in BLAS_THREAD_VARIABLES:
        environ[name] = "1"
    return True


def _register(modules) -> None:
    for module in dict.fromkeys(modules):
        importlib.import_module(f"wormgear_cli.cli.{module}")


def __getattr__(name: str):
    if name == "app":  # the full app: every command registered
        _register(COMMAND_MODULES.values())
        from wormgear_cli.cli._app import app  # lazy: the full app, only when asked for

        return app
    raise AttributeError(name)


def main() -> None:
    """The ``wormgear`` command.  Before anything heavy is imported: closed standard streams
    are replaced and the stop signals handled (:func:`wormgear_cli.files.start_cli`), so
    Ctrl-C, SIGTERM and SIGHUP are one line and exit 128 + N from the first instruction on;
    once the exit code is known, a late signal ends the process at once with it, quietly."""
    one_blas_thread(os.environ)  # before numpy is imported
    # start-up: what is loaded so far (the interpreter, numpy and typer: the bulk of the heap) is never
    # garbage, so keep the collector from walking it again: a full collection during the command's
    # imports otherwise costs more than all of them (tens of ms)
    gc.freeze()
    code = 0
    try:
        # inside the try: a Ctrl-C while the command's modules load is one line, not a traceback
        from wormgear_cli import files

        files.start_cli()
        code = _run(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        if not isinstance(exc.code, (int, type(None))):
            _say(str(exc.code))
    except KeyboardInterrupt:
        code = _stopped(2)
    except BaseException as exc:
        if type(exc).__name__ == "RunStopped":
            code = _stopped(exc.signum)  # type: ignore[attr-defined]  # a files.RunStopped, matched by name
        elif isinstance(exc, MemoryError):
            del exc  # release what the failed step held before saying so
            code = 2
            from wormgear_cli.files import OUT_OF_MEMORY  # (files may be what failed to load)

            _say(f"error: {OUT_OF_MEMORY}")
        else:
            raise
    _settle(code)

    loaded = sys.modules.get("wormgear_cli.files")
    if loaded is not None and hasattr(loaded, "ignore_stop_signals"):
        atexit.register(loaded.ignore_stop_signals)  # the interpreter's last steps: nothing to stop
    sys.exit(code)


def _run(args: list[str]) -> int:
    # lazy: keeps cli._app off `import wormgear_cli.cli`'s start-up
    from wormgear_cli.cli._app import single_command_app

    name = args[0] if args and not args[0].startswith("-") else None
    if name in COMMAND_MODULES:
        _register([COMMAND_MODULES[name]])
        single = single_command_app(name)
    else:
        single = None
    (single or __getattr__("app"))(prog_name="wormgear")
    return 0


def _settle(code: int) -> None:
    files = sys.modules.get("wormgear_cli.files")
    if files is not None and hasattr(files, "settle"):
        files.settle(code)


def _stopped(signum: int) -> int:
    """A stop signal outside a command's run (while the program loads): nothing was written."""
    code = 128 + signum
    _settle(code)
    name = "interrupted" if signum == signal.SIGINT else f"stopped by {signal.Signals(signum).name}"
    _say(f"{name}; no output written")
    return code


def _say(line: str) -> None:
    try:
        sys.stderr.write(line + "\n")
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass


__all__ = ["app", "main", "COMMAND_MODULES"]

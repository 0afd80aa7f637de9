"""Input and output files under faults: bounded reads, checked writes, one output transaction.

Promises kept here (docs/reliability.md states them for users):

* Every input file is read through :func:`read_text_file`: at most
  :data:`MAX_INPUT_BYTES`, refused early when binary, never read forever
  (``/dev/zero``, an endless pipe).
* Every output file goes through :func:`atomic_write`; inside
  :func:`output_transaction` (one per command run) all outputs are staged
  first and committed together at the end, so a failed or interrupted run
  leaves no output.  Staged files are named
  ``.NAME.wormgear-HOST-PID-RANDOM.tmp``; a later run writing into the same
  folder removes those of this host whose process is gone (SIGKILL cannot be
  caught).
* Special files (FIFO, device, socket) and symlinks to them are written in
  place, never renamed over; a symlink to a regular file keeps the link and
  has its final target replaced.
* No output may be an input of the run (:func:`refuse_input`).
* Every write, to files and to stdout (:func:`write_stdout`), is completed
  (short writes resumed) and checked; a failure is a :class:`UsageError`
  (exit 2), a closed pipe on stdout is :class:`StdoutClosed` (a quiet exit).
"""

from __future__ import annotations

import errno
import os
import re
import signal
import stat
import sys
from contextlib import contextmanager
from pathlib import Path

from wormgear_cli.errors import UsageError

#: largest input file (drive spec or measurement CSV) any command reads [bytes]; the TOML
#: guard (:mod:`wormgear_cli.spec.toml`) has a smaller limit of its own for drive files
MAX_INPUT_BYTES = 16 * 1024 * 1024

#: bytes read per step by :func:`read_text_file` (binary content is refused after the first one)
_READ_CHUNK = 1024 * 1024

#: exit code of a run whose stdout was closed by its reader (``| head -1``): 0.  A reader that
#: has read what it wanted is normal use, not a failure (so ``set -o pipefail`` scripts keep
#: working); never 1 ("a check failed").  Outputs to files are still discarded.
BROKEN_PIPE_EXIT = 0

#: signals that stop a run like Ctrl-C (outputs discarded, exit 128 + signal number)
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))

#: file-name pieces of staged files: ".NAME.wormgear-HOST-PID-RANDOM.tmp"
_TMP_TAG = ".wormgear-"
_TMP_PATTERN = r"^\..*\.wormgear-(?P<host>[A-Za-z0-9]*)-(?P<pid>[0-9]+)-[A-Za-z0-9_-]+\.tmp$"
_NAME_KEEP = 100  # characters of the destination name kept in a staged file's name (NAME_MAX is 255)


class StdoutClosed(Exception):
    """The reader of stdout went away (EPIPE): the run stops quietly, exit :data:`BROKEN_PIPE_EXIT`."""


# --- reading ------------------------------------------------------------------------


def read_text_file(path: str | Path, expected: str, error: type = UsageError, encoding: str = "utf-8",
                   max_bytes: int = MAX_INPUT_BYTES) -> str:
    """The text of a user-named input file, or ``error`` with one line saying why not.

    Parameters
    ----------
    path : str or Path
        The file (a regular file, or a pipe/device read until end of file).
    expected : str
        What the file should be ("a TOML drive file", "a CSV file"), for messages.
    error : type
        The :class:`~wormgear_cli.errors.WormgearError` subclass raised.
    encoding : str
        Text encoding ("utf-8-sig" tolerates a byte-order mark).
    max_bytes : int
        Largest accepted size [bytes]; default :data:`MAX_INPUT_BYTES`.

    Raises
    ------
    error
        Missing file, a directory, unreadable, larger than ``max_bytes`` (a
        regular file is refused from its size before reading; anything else
        after reading ``max_bytes + 1`` bytes at most), binary (a NUL byte,
        refused at the first chunk that has one) or not valid in ``encoding``.
    """
    path = Path(path)
    name = str(path)
    if not path.exists():
        raise error(f"{name}: file not found")
    if path.is_dir():
        raise error(f"{name}: is a directory, expected {expected}")
    limit = _size_text(max_bytes)
    chunks = []
    total = 0
    try:
        with open(path, "rb", buffering=0) as fh:
            st = os.fstat(fh.fileno())
            if stat.S_ISREG(st.st_mode) and st.st_size > max_bytes:
                raise error(f"{name}: {_size_text(st.st_size)}, larger than the {limit} accepted; "
                            f"expected {expected}")
            while True:
                chunk = fh.read(min(_READ_CHUNK, max_bytes + 1 - total))
                if not chunk:
                    break
                if b"\x00" in chunk:
                    raise error(f"{name}: binary file, expected {expected}")
                chunks.append(chunk)
                total += len(chunk)
                if total > max_bytes:
                    raise error(f"{name}: more than the {limit} accepted; expected {expected}")
    except OSError as exc:
        raise error(f"{name}: cannot read ({exc.strerror})") from None
    _remember_input(path)
    blob = b"".join(chunks)
    try:
        if encoding == "utf-8-sig":  # the same text, without importing the utf_8_sig codec (start-up)
            text = blob.decode("utf-8")
            return text[1:] if text.startswith("\ufeff") else text
        return blob.decode(encoding)
    except UnicodeDecodeError as exc:
        raise error(f"{name}: not UTF-8 text (byte {exc.start}), expected {expected}") from None


def _size_text(n: int) -> str:
    if n >= 1024 * 1024 and n % (1024 * 1024) == 0:
        return f"{n // (1024 * 1024)} MiB"
    if n >= 1024 * 1024:
        return f"{n / (1024 * 1024):.1f} MiB"
    return f"{n} bytes"


# --- inputs are never outputs ---------------------------------------------------------


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def refuse_input(output: str | Path | None, inputs=(), option: str = "-o") -> None:
    """The one check that an output does not name an input of the run.

    Parameters
    ----------
    output : str, Path or None
        The output file named by the user (None: nothing to check).
    inputs : iterable of str, Path or None
        The run's input files; files read by :func:`read_text_file` in the
        current :func:`output_transaction` are checked too.
    option : str
        The option naming ``output`` ("-o", "--plot"), for the message.

    Raises
    ------
    UsageError
        ``output`` is the same file as an input (same path, or same file
        through a link), or the same path as an input that does not exist yet.
    """
    if output is None or str(output) == "-":
        return
    out = Path(output)
    seen = list(inputs) + (list(_CURRENT.read) if _CURRENT is not None else [])
    for src in seen:
        if src is None or str(src) == "-":
            continue
        src = Path(src)
        same = _same_file(out, src)
        if not same:
            try:
                same = out.resolve() == src.resolve()
            except (OSError, RuntimeError):
                same = False
        if same and not _is_special(out):  # /dev/stdin in, /dev/stdout out on one terminal is fine
            raise UsageError(f"{output}: refusing to overwrite the input file; choose another {option}")


def _is_special(path: Path) -> bool:
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def _remember_input(path: Path) -> None:
    if _CURRENT is not None:
        _CURRENT.read.append(path)


# --- what an output path is -------------------------------------------------------------


def refuse_same_outputs(outputs) -> None:
    """The one check that a run's outputs name different files.

    Parameters
    ----------
    outputs : iterable of (path or None, option name)
        The outputs named by the user, e.g. ``[(output, "-o"), (plot, "--plot")]``; None and
        ``-`` (stdout) are skipped.

    Raises
    ------
    UsageError
        Two options name the same file (same path, or the same file through a link).
    """
    named = [(Path(p), opt) for p, opt in outputs if p is not None and str(p) != "-"]
    for i, (a, opt_a) in enumerate(named):
        for b, opt_b in named[i + 1:]:
            try:
                same = _same_file(a, b) or a.resolve() == b.resolve()
            except OSError:
                same = False
            if same:
                raise UsageError(f"{b}: {opt_a} and {opt_b} name the same file")


def check_output_path(path: str | Path | None, option: str = "-o") -> None:
    """Refuse early (before any work) an output path that can never be written.

    Raises
    ------
    UsageError
        ``path`` is a directory (or a symlink to one), or its folder does not exist.
    """
    if path is None or str(path) == "-":
        return
    _destination(Path(path), option)


def _destination(path: Path, option: str | None = None) -> tuple[str, Path]:
    """``("file", where to rename to)`` for a new or regular file, ``("special", path)`` for a
    file written in place.  Decided from the path itself (``os.lstat``), then from what a
    symlink points at (``os.stat``): a symlink is never renamed over."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return "file", _in_existing_folder(path, option)
    except OSError as exc:
        raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
    if stat.S_ISDIR(st.st_mode):
        raise UsageError(f"{path}: is a directory, expected a file name{_for(option)}")
    if stat.S_ISREG(st.st_mode):
        return "file", path
    if not stat.S_ISLNK(st.st_mode):
        return "special", path  # FIFO, character/block device, socket
    real = Path(os.path.realpath(path))
    try:
        target = os.stat(path)
    except FileNotFoundError:  # dangling link: create its target, keep the link
        return "file", _in_existing_folder(real, option)
    except OSError as exc:
        raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
    if stat.S_ISDIR(target.st_mode):
        raise UsageError(f"{path}: is a directory, expected a file name{_for(option)}")
    if stat.S_ISREG(target.st_mode):
        try:
            same = os.stat(real)
        except OSError:
            same = None
        if same is not None and (same.st_dev, same.st_ino) == (target.st_dev, target.st_ino):
            return "file", real  # replace the link's final target, keep the link
    # a special file behind the link, or a link whose target has no name (/proc/self/fd/N
    # of a deleted file): written in place through the link
    return "special", path


def _for(option: str | None) -> str:
    return f" for {option}" if option else ""


def _in_existing_folder(path: Path, option: str | None) -> Path:
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise UsageError(f"{path}: folder {folder} does not exist{_for(option)}")
    return path


# --- checked writing -------------------------------------------------------------------


def _write_all(fd: int, data: bytes) -> None:
    """Write every byte of ``data`` to ``fd``: resumes short writes, waits on a non-blocking
    descriptor; OSError on failure (ENOSPC, EIO, EPIPE, ...)."""
    view = memoryview(data)
    while view:
        try:
            n = os.write(fd, view)
        except BlockingIOError:
            import select

            select.select([], [fd], [])
            continue
        if n <= 0:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        view = view[n:]


def _as_bytes(data: str | bytes) -> bytes:
    return data if isinstance(data, bytes) else data.encode("utf-8")


def _stdout_failed(exc: OSError):
    # fd 1 is useless now; point it at /dev/null so the interpreter's final flush of
    # sys.stdout cannot fail again (no "Exception ignored" message, no exit code 120)
    fd = _stdout_fd()
    if fd is not None:
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, fd)
            os.close(devnull)
        except OSError:
            pass
    if isinstance(exc, BrokenPipeError) or exc.errno == errno.EPIPE:
        raise StdoutClosed() from None
    raise UsageError(f"stdout: cannot write ({exc.strerror or exc}); is the disk full or the "
                     f"output closed?") from None


def _stdout_fd() -> int | None:
    try:
        return sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # a capture (tests) or a closed stream
        return None


def write_stdout(data: str | bytes) -> None:
    """Write a result to stdout completely, or fail with one line.

    Text is written as UTF-8 (the same bytes as ``-o FILE``).  Anything
    already buffered in ``sys.stdout`` goes first.  Short writes are resumed.

    Parameters
    ----------
    data : str or bytes
        The whole result (text is encoded as UTF-8, newlines untouched).

    Raises
    ------
    StdoutClosed
        The reader closed the pipe (``| head``): the caller stops quietly.
    UsageError
        Any other write error (ENOSPC on a full disk, EIO, EFBIG, ...).
    """
    blob = _as_bytes(data)
    try:
        sys.stdout.flush()
        fd = _stdout_fd()
        if fd is None:
            buf = getattr(sys.stdout, "buffer", None)
            if buf is not None:
                buf.write(blob)
                buf.flush()
            else:
                sys.stdout.write(blob.decode("utf-8"))
                sys.stdout.flush()
            return
        _write_all(fd, blob)
    except OSError as exc:
        _stdout_failed(exc)


def flush_stdout() -> None:
    """Flush ``sys.stdout`` (text printed with ``print``/``typer.echo``), checked like
    :func:`write_stdout`."""
    try:
        sys.stdout.flush()
    except OSError as exc:
        _stdout_failed(exc)
    except ValueError:  # closed by a caller
        pass


# --- signals ---------------------------------------------------------------------------


@contextmanager
def signals_deferred():
    """Hold back :data:`STOP_SIGNALS` for the block (delivered after it): renaming or
    removing a set of staged files is never cut in half."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


# --- the output transaction ---------------------------------------------------------------


class _Transaction:
    """Outputs of one command run, written together at the end (all or nothing)."""

    def __init__(self) -> None:
        self.staged: list[tuple[str, Path]] = []  # (temporary file, destination)
        self.direct: list[tuple[Path, bytes]] = []  # special files (FIFO, device): written at commit
        self.read: list[Path] = []  # input files read in this run (never overwritten)
        self.committed: list = []  # callbacks run once every output is in place

    def commit(self) -> None:
        """Write the special files, then rename the staged files into place.  A failure
        discards what is left and raises UsageError; nothing is renamed before every
        output has been written."""
        dest = None
        try:
            # special files first, interruptible (opening a FIFO waits for its reader)
            for dest, data in self.direct:
                _write_direct(dest, data)
            with signals_deferred():  # the renames are quick and never cut in half
                for tmp, dest in list(self.staged):
                    os.replace(tmp, dest)
                    self.staged.pop(0)
        except BaseException as exc:
            self.discard()
            if isinstance(exc, OSError):
                if exc.errno == errno.EPIPE:
                    raise StdoutClosed() from None
                raise UsageError(f"{dest}: cannot write ({exc.strerror})") from None
            raise
        self.staged, self.direct = [], []
        callbacks, self.committed = self.committed, []
        for callback in callbacks:
            callback()

    def discard(self) -> None:
        with signals_deferred():
            for tmp, _ in self.staged:
                _unlink_quietly(tmp)
            self.staged, self.direct, self.committed = [], [], []


def after_commit(callback) -> None:
    """Run ``callback()`` once the run's outputs are all in place (at once outside an
    :func:`output_transaction`; never when the run fails).  "wrote FILE" messages use it, so
    a run that fails or is stopped never claims a file it did not leave."""
    if _CURRENT is None:
        callback()
    else:
        _CURRENT.committed.append(callback)


_CURRENT: _Transaction | None = None


@contextmanager
def output_transaction():
    """Defer every :func:`atomic_write` inside the block (files are staged as
    temporary files at once, so write errors surface early); rename them all into
    place when the block ends normally, discard them when it raises, so a failed
    run leaves no output.  A caller that wants to keep the outputs on a particular
    exception calls ``commit()`` on the yielded transaction first."""
    global _CURRENT
    if _CURRENT is not None:  # nested: the outer block decides
        yield _CURRENT
        return
    tx = _Transaction()
    _CURRENT = tx
    try:
        yield tx
    except BaseException:
        _CURRENT = None
        tx.discard()
        raise
    _CURRENT = None
    tx.commit()


def _unlink_quietly(path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def _write_direct(path: Path, data: bytes) -> None:
    """Write in place (a special file, or a file behind a nameless link): never created, every
    byte written."""
    fd = os.open(path, os.O_WRONLY | os.O_TRUNC | getattr(os, "O_CLOEXEC", 0))
    try:
        _write_all(fd, data)
    finally:
        os.close(fd)


# --- staged files and their leftovers ---------------------------------------------------


def _host_tag() -> str:
    if hasattr(os, "uname"):
        node = os.uname().nodename
    else:  # pragma: no cover - not POSIX
        import platform

        node = platform.node()
    return "".join(c for c in node if c.isascii() and c.isalnum())[:16]


def _staged_name(dest: Path) -> str:
    return f".{dest.name[:_NAME_KEEP]}{_TMP_TAG}{_host_tag()}-{os.getpid()}-{os.urandom(4).hex()}.tmp"


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return True  # not a process we could have been: leave the file alone
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


_SWEPT: set[str] = set()


def remove_stale_staged(folder: str | Path) -> list[str]:
    """Remove staged files left in ``folder`` by runs of this program that were killed
    (SIGKILL, power loss): names matching ``.NAME.wormgear-HOST-PID-RANDOM.tmp`` with this
    host's tag, owned by this user, whose process PID no longer exists.  Returns the names
    removed.  Files of live processes, of other hosts (a shared network folder) or other
    users are left alone."""
    removed = []
    host, me, uid = _host_tag(), os.getpid(), os.getuid() if hasattr(os, "getuid") else None
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        if _TMP_TAG not in entry.name:
            continue
        m = re.match(_TMP_PATTERN, entry.name, re.S)
        if m is None or m.group("host") != host:
            continue
        pid = int(m.group("pid"))
        if pid == me or _pid_alive(pid):
            continue
        try:
            st = entry.stat(follow_symlinks=False)
        except OSError:
            continue
        if not stat.S_ISREG(st.st_mode) or (uid is not None and st.st_uid != uid):
            continue
        _unlink_quietly(entry.path)
        removed.append(entry.name)
    return removed


def _sweep_once(folder: Path) -> None:
    key = os.path.abspath(folder)
    if key not in _SWEPT:
        _SWEPT.add(key)
        remove_stale_staged(folder)


def atomic_write(path: str | Path, data: str | bytes, inputs: tuple = (), option: str | None = None) -> None:
    """Write ``data`` to ``path`` so that readers never see a half-written file and a
    failed run leaves nothing behind.

    A new or regular file is written to a staged file in the same folder and
    renamed over ``path`` (inside :func:`output_transaction`: at the end of the
    command, together with the other outputs).  A symlink to a regular file
    keeps the link; its final target is replaced.  A special file (FIFO,
    device such as /dev/null) or a symlink to one is written in place, at
    commit.  Text is written as UTF-8, bytes as they are.  :func:`atomic_stream`
    does the same for content written piece by piece.

    Parameters
    ----------
    path : str or Path
        The output named by the user.
    data : str or bytes
        The whole content.
    inputs : tuple of str or Path
        Input files of the run that ``path`` must not be (see :func:`refuse_input`).
    option : str or None
        The option that named ``path`` ("-o", "--plot"), for messages.

    Raises
    ------
    UsageError
        ``path`` is an input (:func:`refuse_input`), a directory, in a missing
        folder, or cannot be written (one line with the system's reason).
    StdoutClosed
        ``path`` is a pipe whose reader went away.
    """
    with atomic_stream(path, inputs, option) as write:
        write(data)


@contextmanager
def atomic_stream(path: str | Path, inputs: tuple = (), option: str | None = None):
    """:func:`atomic_write` for content produced piece by piece: yields ``write(chunk)``
    (str or bytes) that appends to the staged file, so a large output is never held in
    memory whole.  The staged file becomes ``path`` when the block ends without an error
    (inside :func:`output_transaction`: at commit); on any error it is removed.  A special
    file is written at commit (its content is held until then).  Raises as :func:`atomic_write`.
    """
    path = Path(path)
    refuse_input(path, inputs, option or "-o")
    kind, dest = _destination(path, option)
    if kind == "special":
        pieces: list[bytes] = []
        yield lambda chunk: pieces.append(_as_bytes(chunk))
        blob = b"".join(pieces)
        if _CURRENT is not None:
            _CURRENT.direct.append((path, blob))
            return
        try:
            _write_direct(path, blob)
        except OSError as exc:
            if exc.errno == errno.EPIPE:
                raise StdoutClosed() from None
            raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
        return
    folder = dest.parent if str(dest.parent) else Path(".")
    _sweep_once(folder)
    tmp = folder / _staged_name(dest)
    try:
        mode = stat.S_IMODE(os.stat(dest).st_mode)
    except OSError:
        mode = None
    fd = None
    try:
        with signals_deferred():  # the staged file is registered as soon as it exists
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
            if _CURRENT is not None:
                _CURRENT.staged.append((str(tmp), dest))
        yield lambda chunk: _write_all(fd, _as_bytes(chunk))
        fd, _fd = None, fd
        os.close(_fd)  # a deferred write error (NFS, quota) surfaces here
        if mode is not None:
            os.chmod(tmp, mode)  # an existing file keeps its permissions
        if _CURRENT is None:
            os.replace(tmp, dest)
    except BaseException as exc:
        if fd is not None:
            try:
                os.close(fd)
            except OSError:
                pass
        with signals_deferred():
            _unlink_quietly(tmp)
            if _CURRENT is not None:
                _CURRENT.staged = [(t, d) for t, d in _CURRENT.staged if t != str(tmp)]
        if isinstance(exc, OSError):
            raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
        raise

"""Input and output files under faults: bounded reads, checked writes, one output transaction.

Promises kept here (docs/reliability.md states them for users, and names the test of each):

* Every input file is read through :func:`read_text_file`: at most
  :data:`MAX_INPUT_BYTES`, refused early when binary or when one line is longer than the
  caller allows, never read forever (``/dev/zero``, an endless pipe).
* Every output file goes through :func:`atomic_write` / :func:`atomic_stream`; inside
  :func:`output_transaction` (one per command run) all outputs are staged first and
  committed together at the end: every staged file complete and synced before the first
  rename; a rename that fails puts back the files already replaced (from kept copies), so a
  failed or interrupted run leaves no output.  Staged files are named
  ``.NAME.wormgear-HOST-PID-RANDOM.tmp``; a later run writing into the same folder removes
  those of this host whose process is gone (SIGKILL cannot be caught).
* What an output path is decides how it is written (:func:`check_output_path`): a
  descriptor named as a path (``/dev/stdout``, ``/dev/fd/N``, ``/proc/self/fd/N``) is
  written through that descriptor at once, exactly like ``-`` (appending where it
  appends); a FIFO or a device is written in place at commit; a regular file is staged and
  renamed, keeping its owner, group and mode where the caller may; a file the caller could
  not write with a shell's ``>`` is refused, and so is a symlink (or file) of another user
  in a sticky world-writable folder (the kernel's ``protected_symlinks`` and
  ``protected_regular`` rules).
* No output may be an input of the run (:func:`refuse_input`).
* Every write, to files and to stdout (:func:`write_stdout`), is completed
  (short writes resumed) and checked; a failure is a :class:`UsageError`
  (exit 2), a closed pipe on stdout is :class:`StdoutClosed` (a quiet exit).
* The command line's process (:func:`start_cli`): closed standard streams are
  replaced before anything else is opened; SIGINT, SIGTERM and SIGHUP stop a
  run (:class:`RunStopped`) from the first instruction; once a run's outcome is
  settled (its outputs committed), a late signal ends it at once with that
  outcome's exit code, quietly.
* What the machine can hold (:func:`check_memory`): sizes are checked against the memory a
  run may use before the work (``WORMGEAR_MEMORY`` overrides what the system says).

Writing outputs from other modules (a stable API): inside a command run (the CLI wraps each
in :func:`output_transaction`) write every file with :func:`atomic_write` or
:func:`atomic_stream` -- it is staged at once (write errors surface early) and committed with
every other output at the end; announce it with :func:`after_commit`.  ``exclusive=True``
never replaces an existing file; ``alone=True`` commits that one file at once (a finished
part of a resumable run), untouched by a later failure of the run.  Outside a transaction
each call commits at once.  Inputs read with :func:`read_text_file` are protected from
being overwritten by any output of the same run.
"""

from __future__ import annotations

import errno
import os
import platform
import re
import select
import signal
import stat
import sys
import threading
from contextlib import contextmanager
from pathlib import Path

from wormgear_cli.errors import UsageError, quote

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

#: file-name pieces of staged files (and of the copies kept during a commit):
#: ".NAME.wormgear-HOST-PID-RANDOM.tmp"
_TMP_TAG = ".wormgear-"
_TMP_PATTERN = r"^\..*\.wormgear-(?P<host>[A-Za-z0-9]*)-(?P<pid>[0-9]+)-[A-Za-z0-9_-]+\.tmp$"
_NAME_KEEP = 100  # characters of the destination name kept in a staged file's name (NAME_MAX is 255)

#: a descriptor named as a path; PID must be this process (``/proc/self`` resolves to it)
_FD_PATH = re.compile(r"/(?:dev/fd|proc/(?P<pid>self|thread-self|\d+)(?:/task/\d+)?/fd)/(?P<fd>\d+)")

#: symlinks followed in one path before giving up (the kernel's ELOOP limit)
_MAX_LINKS = 40


class StdoutClosed(Exception):
    """The reader of stdout went away (EPIPE): the run stops quietly, exit :data:`BROKEN_PIPE_EXIT`."""


class RunStopped(BaseException):
    """SIGTERM or SIGHUP arrived: the run stops like Ctrl-C (outputs discarded, exit 128 + N).

    A BaseException, so ``except Exception`` in command code cannot swallow it."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


# --- reading ------------------------------------------------------------------------


def read_text_file(path: str | Path, expected: str, error: type = UsageError, encoding: str = "utf-8",
                   max_bytes: int = MAX_INPUT_BYTES, max_line_bytes: int | None = None) -> str:
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
    max_line_bytes : int or None
        Longest accepted line [bytes] (None: no limit of its own).  A longer line is
        refused as soon as that many bytes have been read without a line end, so a file
        of one endless line costs no more than this.

    Raises
    ------
    error
        Missing file, a directory, unreadable, larger than ``max_bytes`` (a
        regular file is refused from its size before reading; anything else
        after reading ``max_bytes + 1`` bytes at most), binary (a NUL byte,
        refused at the first chunk that has one), a line longer than
        ``max_line_bytes``, or not valid in ``encoding``.
    """
    path = Path(path)
    chunks = list(_checked_chunks(path, expected, error, max_bytes, max_line_bytes))
    _remember_input(path)
    blob = b"".join(chunks)
    del chunks
    try:
        if encoding == "utf-8-sig":  # the same text, without importing the utf_8_sig codec (start-up)
            text = blob.decode("utf-8")
            return text[1:] if text.startswith("\ufeff") else text
        return blob.decode(encoding)
    except UnicodeDecodeError as exc:
        raise error(f"{quote(path)}: not UTF-8 text (byte {exc.start}), expected {expected}") from None


def check_text_file(path: str | Path, expected: str, error: type = UsageError, max_bytes: int = MAX_INPUT_BYTES,
                    max_line_bytes: int | None = None) -> tuple[os.stat_result, int]:
    """Every check of :func:`read_text_file` (UTF-8 text) on a regular file, in one pass that keeps
    nothing of it: for inputs read afterwards block by block (a measurement of millions of rows is
    never held whole).  The same messages, in the same order: a problem anywhere in the file
    (binary, a line too long) is said before a UTF-8 error, as when the file is decoded whole.

    Returns the file's status when it was opened (size, modification time, inode), so that a
    reader can tell when the file changed before it read it again, and its number of lines (line
    ends + 1).

    Raises
    ------
    error
        As :func:`read_text_file`.
    """
    path = Path(path)
    first_bad = None  # byte of the first invalid UTF-8 sequence
    offset = 0
    carry = b""
    opened: list = []
    lines = 1
    for chunk in _checked_chunks(path, expected, error, max_bytes, max_line_bytes, opened):
        lines += chunk.count(b"\n")
        if first_bad is not None:
            continue
        data = carry + chunk if carry else chunk
        cut = data.rfind(b"\n") + 1  # UTF-8 sequences never contain a line end: whole pieces decode alone
        piece, carry = data[:cut], data[cut:]
        first_bad = _utf8_error(piece, offset)
        offset += cut
    if first_bad is None and carry:
        first_bad = _utf8_error(carry, offset)
    _remember_input(path)
    if first_bad is not None:
        raise error(f"{quote(path)}: not UTF-8 text (byte {first_bad}), expected {expected}")
    return opened[0], lines


def _utf8_error(piece: bytes, offset: int) -> int | None:
    """Byte (from the file's start) of the first invalid UTF-8 sequence of ``piece``, else None."""
    if piece.isascii():
        return None
    try:
        piece.decode("utf-8")
    except UnicodeDecodeError as exc:
        return offset + exc.start
    return None


def _checked_chunks(path: Path, expected: str, error: type, max_bytes: int, max_line_bytes: int | None,
                    opened: list | None = None):
    """The bytes of ``path`` in chunks, each checked as :func:`read_text_file` says (missing,
    directory, size, binary, line length, read errors); ``opened`` gets the file's status."""
    name = quote(path)
    if not path.exists():
        raise error(f"{name}: file not found")
    if path.is_dir():
        raise error(f"{name}: is a directory, expected {expected}")
    limit = _size_text(max_bytes)
    step = _READ_CHUNK if max_line_bytes is None else max(1, min(_READ_CHUNK, max_line_bytes))
    total = lines = run = 0  # run: bytes since the last line end
    try:
        with open(path, "rb", buffering=0) as fh:
            st = os.fstat(fh.fileno())
            if opened is not None:
                opened.append(st)
            if stat.S_ISREG(st.st_mode) and st.st_size > max_bytes:
                raise error(f"{name}: {_size_text(st.st_size)}, larger than the {limit} accepted; "
                            f"expected {expected}")
            while True:
                chunk = fh.read(min(step, max_bytes + 1 - total))
                if not chunk:
                    break
                if b"\x00" in chunk:
                    raise error(f"{name}: binary file, expected {expected}")
                if max_line_bytes is not None:  # a line inside one chunk is shorter than the limit
                    first = chunk.find(b"\n")
                    if run + (len(chunk) if first < 0 else first) > max_line_bytes:
                        raise error(f"{name}:{lines + 1}: a line longer than {_size_text(max_line_bytes)}; "
                                    f"expected {expected}")
                    n = chunk.count(b"\n")
                    lines += n
                    run = run + len(chunk) if n == 0 else len(chunk) - chunk.rfind(b"\n") - 1
                total += len(chunk)
                if total > max_bytes:
                    raise error(f"{name}: more than the {limit} accepted; expected {expected}")
                yield chunk
    except OSError as exc:
        raise error(f"{name}: cannot read ({exc.strerror})") from None


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
            raise UsageError(f"{quote(output)}: refusing to overwrite the input file; choose another {option}")


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
                raise UsageError(f"{quote(b)}: {opt_a} and {opt_b} name the same file")


def check_outputs(outputs, inputs=()) -> None:
    """Every output of a run checked before any work: each a path that may be written
    (:func:`check_output_path`) and not an input (:func:`refuse_input`), and no two the same
    file (:func:`refuse_same_outputs`).  ``outputs``: (path or None, option name) pairs;
    ``inputs``: the run's input files.  Raises UsageError."""
    outputs = list(outputs)
    for path, option in outputs:
        check_output_path(path, option)
        refuse_input(path, inputs, option)
    refuse_same_outputs(outputs)


def check_output_path(path: str | Path | None, option: str = "-o") -> None:
    """Refuse early (before any work) an output path that can never be written.

    Raises
    ------
    UsageError
        ``path`` is a directory (or a symlink to one), its folder does not exist, it is a
        file the caller may not write (as a shell's ``>`` would refuse it), or it goes
        through a symlink of another user in a sticky world-writable folder.
    """
    if path is None or str(path) == "-":
        return
    _destination(Path(path), option)


def descriptor_of(path: str | Path | None) -> int | None:
    """N when ``path`` names this process's descriptor N (``/dev/stdout``, ``/dev/fd/N``,
    ``/proc/self/fd/N``, or a symlink to one), else None.  Such a path is written through the
    descriptor at once, exactly like ``-`` (``/dev/stdout``: 1, so it *is* stdout)."""
    if path is None or str(path) == "-":
        return None
    try:
        fd = _follow(Path(path), None)[1]
    except UsageError:
        return None
    return fd if fd is not None and fd >= 0 else None


def names_a_descriptor(path: str | Path | None) -> bool:
    """True when ``path`` names one of this process's descriptors (:func:`descriptor_of`):
    written like ``-``, no "wrote" line is due."""
    return descriptor_of(path) is not None


def _destination(path: Path, option: str | None = None) -> tuple[str, Path, int | None]:
    """How ``path`` is written: ``("descriptor", path, N)`` through this process's descriptor
    N at once; ``("special", path, None)`` in place at commit (FIFO, device, socket, another
    process's descriptor); ``("file", where to rename to, None)`` for a new or regular file
    (a symlink is never renamed over: its final target is).  Decided by following the path
    as the kernel would (:func:`_follow`), then from what it ends at (``os.stat``)."""
    real, fd, links = _follow(path, option)
    if fd is not None:
        return ("descriptor", path, fd) if fd >= 0 else ("special", path, None)
    shown = path if links == 0 else Path(real)
    try:
        st = os.stat(real)
    except (FileNotFoundError, NotADirectoryError):
        return "file", _in_existing_folder(shown, option), None
    except OSError as exc:
        raise UsageError(f"{quote(path)}: cannot write ({exc.strerror})") from None
    if stat.S_ISDIR(st.st_mode):
        raise UsageError(f"{quote(path)}: is a directory, expected a file name{_for(option)}")
    if stat.S_ISREG(st.st_mode):
        _refuse_unwritable(path, real, st, option)
        return "file", shown, None
    return "special", shown, None


def _follow(path: Path, option: str | None) -> tuple[str, int | None, int]:
    """Resolve ``path`` component by component as ``open`` does: ``(real path, descriptor,
    symlinks followed)``.  The descriptor is N for a path naming this process's descriptor N,
    -1 for another process's, None otherwise.  A path that stops existing part-way is
    returned joined as given from there.  Every symlink followed is checked as the kernel's
    ``protected_symlinks`` does (:func:`_refuse_foreign_link`)."""
    text = os.fspath(path)
    cur = "/" if text.startswith("/") else os.getcwd()
    pending = [p for p in reversed(text.split("/")) if p not in ("", ".")]
    links = 0
    while pending:
        name = pending.pop()
        if name == "..":
            cur = os.path.dirname(cur)
            continue
        nxt = os.path.join(cur, name)
        if not pending:
            m = _FD_PATH.fullmatch(nxt)
            if m is not None:
                pid = m.group("pid")
                ours = pid in (None, "self", "thread-self") or int(pid) == os.getpid()
                return nxt, int(m.group("fd")) if ours else -1, links
        try:
            st = os.lstat(nxt)
        except (FileNotFoundError, NotADirectoryError):
            return os.path.join(nxt, *reversed(pending)), None, links
        except OSError as exc:
            raise UsageError(f"{quote(path)}: cannot write ({exc.strerror})") from None
        if not stat.S_ISLNK(st.st_mode):
            cur = nxt
            continue
        links += 1
        if links > _MAX_LINKS:
            raise UsageError(f"{quote(path)}: cannot write (Too many levels of symbolic links)")
        _refuse_foreign_link(path, nxt, st, cur, option)
        target = os.readlink(nxt)
        if target.startswith("/"):
            cur = "/"
        pending.extend(p for p in reversed(target.split("/")) if p not in ("", "."))
    return cur, None, links


def _shared_folder(folder: str):
    """``os.stat`` of ``folder`` when it is sticky and world-writable (/tmp), else None."""
    try:
        st = os.stat(folder)
    except OSError:
        return None
    return st if st.st_mode & stat.S_ISVTX and st.st_mode & stat.S_IWOTH else None


def _euid() -> int:
    return os.geteuid() if hasattr(os, "geteuid") else 0


def _refuse_foreign_link(path: Path, link: str, st: os.stat_result, folder: str, option: str | None) -> None:
    """Refuse to follow a symlink of another user in a sticky world-writable folder unless the
    folder is that user's: the kernel's ``fs.protected_symlinks`` rule, kept whatever the
    setting (a rename follows no such rule: it would replace the link's target)."""
    shared = _shared_folder(folder)
    if shared is not None and st.st_uid != _euid() and st.st_uid != shared.st_uid:
        raise UsageError(f"{quote(path)}: not following {quote(link)}, a symlink of another user (uid "
                         f"{st.st_uid}) in the shared folder {quote(folder)}; choose another {option or 'output'}")


def _refuse_unwritable(path: Path, real: str, st: os.stat_result, option: str | None) -> None:
    """Refuse to replace a file that a shell's ``>`` could not write: one the caller has no
    write permission for (``chmod 444``, another user's), one on a read-only file system, or
    another user's file in a sticky world-writable folder not theirs (``fs.protected_regular``)."""
    folder = os.path.dirname(real) or "."
    shared = _shared_folder(folder)
    if shared is not None and st.st_uid != _euid() and st.st_uid != shared.st_uid:
        raise UsageError(f"{quote(path)}: a file of another user (uid {st.st_uid}) in the shared folder "
                         f"{quote(folder)}; not replaced, choose another {option or 'output'}")
    eff = os.access in os.supports_effective_ids
    if os.access(real, os.W_OK, effective_ids=eff):
        return
    try:
        read_only = bool(os.statvfs(folder).f_flag & getattr(os, "ST_RDONLY", 1))
    except (OSError, AttributeError):
        read_only = False
    if read_only:
        raise UsageError(f"{quote(path)}: cannot write (Read-only file system)")
    raise UsageError(f"{quote(path)}: cannot write (Permission denied); the file is read-only for you "
                     f"(mode {stat.S_IMODE(st.st_mode):o}): make it writable or choose another {option or 'output'}")


def _for(option: str | None) -> str:
    return f" for {option}" if option else ""


def _in_existing_folder(path: Path, option: str | None) -> Path:
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise UsageError(f"{quote(path)}: folder {quote(folder)} does not exist{_for(option)}")
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
    if exc.errno == errno.EBADF:
        raise UsageError("stdout: cannot write (Bad file descriptor); stdout is closed or read-only: name "
                         "a file with -o") from None
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
        Any other write error (ENOSPC on a full disk, EIO, EFBIG, a stdout closed
        when the program started, ...).
    """
    blob = _as_bytes(data)
    try:
        if 1 in _CLOSED_AT_START:
            raise OSError(errno.EBADF, os.strerror(errno.EBADF))
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
    except (ValueError, AttributeError):  # closed by a caller, or no stdout at all
        pass


def _descriptor_writer(path: Path, fd: int):
    """``write(chunk)`` through this process's descriptor ``fd`` (``-o /dev/stdout``,
    ``/dev/fd/3``): at once, where the descriptor stands (appending if it appends), exactly as
    a result on stdout is written; Python's own buffer of stdout or stderr goes first."""
    name = quote(path)

    def write(chunk) -> None:
        try:
            if fd in _CLOSED_AT_START:
                raise OSError(errno.EBADF, os.strerror(errno.EBADF))
            stream = {1: sys.stdout, 2: sys.stderr}.get(fd)
            if stream is not None:
                stream.flush()
            _write_all(fd, _as_bytes(chunk))
        except OSError as exc:
            if exc.errno == errno.EPIPE:
                raise StdoutClosed() from None
            raise UsageError(f"{name}: cannot write ({exc.strerror})") from None

    return write


# --- standard streams and signals ---------------------------------------------------------

#: standard descriptors (0, 1, 2) that were closed when the program started (``>&-``)
_CLOSED_AT_START: frozenset = frozenset()

#: exit code the process ends with, at once, on a stop signal (None: the signal stops the run);
#: set once a run's outcome is settled (:func:`settle`), only in the command line's own process
_EXIT_ON_STOP: int | None = None
_PROCESS_WIDE = False
_STOPS = 0  # stop signals received by the command line's process before its outcome was settled
#: stop signals held back by :func:`signals_deferred` (None: not inside such a block)
_DEFERRED: list[int] | None = None


class _ClosedStream:
    """``sys.stdout`` when descriptor 1 was closed at start: every write fails with EBADF
    (one error line, exit 2), nothing is sent to the null device that stands in for it."""

    encoding = "utf-8"
    errors = "strict"

    def write(self, text):
        raise OSError(errno.EBADF, os.strerror(errno.EBADF))

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        raise OSError(errno.EBADF, os.strerror(errno.EBADF))


def guard_standard_streams() -> frozenset:
    """Make closed standard descriptors harmless (the command line's first act).

    A descriptor 0, 1 or 2 closed by the caller (``>&-``, ``2>&-``, ``<&-``) is opened on the
    null device, so no file the run opens takes its number (an output file would otherwise
    become "stdout").  A closed stdout then refuses every result (one error line, exit 2:
    ``-o FILE`` still works); messages to a closed stderr are dropped.  Returns the
    descriptors that were closed."""
    global _CLOSED_AT_START
    closed = []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            closed.append(fd)
    for fd in closed:
        null = os.open(os.devnull, os.O_RDONLY if fd == 0 else os.O_WRONLY)
        if null != fd:
            os.dup2(null, fd)
            os.close(null)
    if 1 in closed or sys.stdout is None:
        sys.stdout = _ClosedStream()
    if 2 in closed or sys.stderr is None:
        sys.stderr = open(2, "w", encoding="utf-8", errors="backslashreplace", closefd=False)
    if 0 in closed or sys.stdin is None:
        sys.stdin = open(0, encoding="utf-8", closefd=False)
    _CLOSED_AT_START = frozenset(closed)
    return _CLOSED_AT_START


def _stop(signum, frame):
    global _STOPS
    if _DEFERRED is not None:  # inside signals_deferred: handled when the block ends
        _DEFERRED.append(signum)
        return
    if _EXIT_ON_STOP is not None:  # the outcome stands: end now, quietly, with it
        os._exit(_EXIT_ON_STOP)
    if _PROCESS_WIDE:
        _STOPS += 1
        if _STOPS == 2:  # the first one is being handled (staged files removed, its line said)
            return
        if _STOPS > 2:  # and did not end the run: a third one ends it now
            os._exit(128 + signum)
    if signum == getattr(signal, "SIGINT", None):
        raise KeyboardInterrupt
    raise RunStopped(signum)


def install_stop_handlers(process: bool = False):
    """Make SIGINT raise KeyboardInterrupt and SIGTERM, SIGHUP raise :class:`RunStopped`
    (main thread only; a signal the parent set to be ignored, as ``nohup`` does for SIGHUP
    and a shell for SIGINT of a background job, stays ignored).

    Parameters
    ----------
    process : bool
        True in the command line's own process (:func:`start_cli`): :func:`settle` then
        makes a late signal end the process at once.

    Returns
    -------
    callable
        Restores the previous handlers.
    """
    global _PROCESS_WIDE

    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    old = {}
    for signum in STOP_SIGNALS:
        previous = signal.getsignal(signum)
        if previous == signal.SIG_IGN:
            continue
        old[signum] = previous
        signal.signal(signum, _stop)
    if process:
        _PROCESS_WIDE = True

    def restore():
        for signum, handler in old.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)

    return restore


def settle(code: int | None) -> None:
    """The run's outcome is decided (``code``: its exit code; None: not yet).  From now on a
    stop signal in the command line's process ends it at once with ``code`` and no message:
    a committed run stays a success, a second Ctrl-C while exiting shows nothing."""
    global _EXIT_ON_STOP
    if _PROCESS_WIDE or code is None:
        _EXIT_ON_STOP = code


def ignore_stop_signals() -> None:
    """Ignore :data:`STOP_SIGNALS` from now on: the last step of the command line's process
    (an ``atexit`` hook, after the interpreter has joined its threads), so a signal while the
    interpreter tears itself down neither prints nor changes the settled exit code (Python
    resets handlers, not ignored signals, to the default action at that point)."""
    for signum in STOP_SIGNALS:
        try:
            signal.signal(signum, signal.SIG_IGN)
        except (OSError, ValueError):  # pragma: no cover - not the main thread
            pass


def start_cli() -> None:
    """What the command line does before anything else (cheap: no import beyond this module):
    :func:`guard_standard_streams`, then :func:`install_stop_handlers` for the whole process."""
    guard_standard_streams()
    install_stop_handlers(process=True)


@contextmanager
def signals_deferred():
    """Hold back :data:`STOP_SIGNALS` for the block (handled after it): renaming or
    removing a set of staged files is never cut in half.

    Two layers: the signals are blocked for this thread, and a signal that still reaches the
    handler is recorded and handled when the block ends.  The second is needed because a
    process-directed signal is delivered to any thread that does not block it (numpy's
    BLAS threads), and Python then runs the handler in the main thread at once, mask or not."""
    global _DEFERRED
    if _DEFERRED is not None:  # nested: the outer block hands the signals on
        yield
        return
    _DEFERRED = []
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS) if hasattr(signal, "pthread_sigmask") else None
    try:
        yield
    finally:
        held, _DEFERRED = _DEFERRED, None
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)  # a blocked signal is handled here
        if held:
            _stop(held[0], None)


# --- the output transaction ---------------------------------------------------------------


class _Transaction:
    """Outputs of one command run, written together at the end (all or nothing).

    Attributes others may read: ``done`` (None until the outputs are committed, then the
    exit code the run was committed with) and ``read`` (the input files read in the run)."""

    def __init__(self) -> None:
        self.staged: list[tuple[str, Path, bool]] = []  # (staged file, destination, must not exist)
        self.direct: list[tuple[Path, bytes]] = []  # special files (FIFO, device): written at commit
        self.read: list[Path] = []  # input files read in this run (never overwritten)
        self.committed: list = []  # callbacks run once every output is in place
        self.done: int | None = None

    def commit(self, exit_code: int | None = 0) -> None:
        """Write the special files, then put every staged file in place: each one is
        complete and synced before the first rename; a rename that fails puts back the
        files already replaced and raises UsageError (naming any file it could not put
        back).  Once in place the run is settled with ``exit_code`` (:func:`settle`): a
        signal after that does not turn it into a failure (None: a file committed alone,
        the run goes on)."""
        dest = None
        try:
            # special files first, interruptible (opening a FIFO waits for its reader)
            for dest, data in self.direct:
                _write_direct(dest, data)
            with signals_deferred():  # the renames are quick and never cut in half
                self._replace_all()
                self.done = exit_code
                if exit_code is not None:  # a run's outputs: its outcome is settled
                    settle(exit_code)
        except BaseException as exc:
            self.discard()
            if isinstance(exc, OSError):
                if exc.errno == errno.EPIPE:
                    raise StdoutClosed() from None
                raise UsageError(f"{quote(dest)}: cannot write ({exc.strerror})") from None
            raise
        self.staged, self.direct = [], []
        callbacks, self.committed = self.committed, []
        for callback in callbacks:
            callback()

    def _replace_all(self) -> None:
        for tmp, dest, _ in self.staged:  # every staged file is still there (its folder too)
            try:
                os.lstat(tmp)
            except OSError as exc:
                raise UsageError(f"{quote(dest)}: cannot write ({exc.strerror})") from None
        plan = [_Replacement(tmp, dest, exclusive) for tmp, dest, exclusive in self.staged]
        plan.sort(key=lambda r: r.existed and r.kept is None)  # what cannot be undone goes last
        done: list[_Replacement] = []
        try:
            for r in plan:
                r.put_in_place()
                done.append(r)
        except OSError as exc:
            raise UsageError(_undo(done, plan, exc)) from None
        for r in plan:
            r.forget_kept()
        self.staged = []
        for folder in dict.fromkeys(r.folder for r in plan):
            _sync_folder(folder)

    def discard(self) -> None:
        with signals_deferred():
            for tmp, _, _ in self.staged:
                _unlink_quietly(tmp)
            self.staged, self.direct, self.committed = [], [], []


class _Replacement:
    """One staged file going into place, with a kept copy (a hard link) of the file it
    replaces, so a commit that fails later can put the old file back."""

    def __init__(self, tmp: str, dest: Path, exclusive: bool):
        self.tmp, self.dest, self.exclusive = tmp, dest, exclusive
        self.folder = str(dest.parent) if str(dest.parent) else "."
        try:
            self.existed = not exclusive and stat.S_ISREG(os.lstat(dest).st_mode)
        except OSError:
            self.existed = False
        self.kept = None
        if self.existed:
            kept = os.path.join(self.folder, _staged_name(dest))
            try:
                os.link(dest, kept)
                self.kept = kept
            except OSError:  # no hard links here (or not allowed): this one goes last
                pass

    def put_in_place(self) -> None:
        if not self.exclusive:
            os.replace(self.tmp, self.dest)
            return
        try:  # never over a file that appeared meanwhile
            os.link(self.tmp, self.dest)
        except OSError as exc:
            if exc.errno == errno.EEXIST or os.path.lexists(self.dest):
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST)) from None
            os.replace(self.tmp, self.dest)  # a file system without hard links
            return
        _unlink_quietly(self.tmp)

    def put_back(self) -> bool:
        """Undo :meth:`put_in_place`; False when the old file cannot be restored."""
        try:
            if self.kept is not None:
                os.replace(self.kept, self.dest)
                self.kept = None
            elif not self.existed:
                os.unlink(self.dest)
            else:
                return False
        except OSError:
            return False
        return True

    def forget_kept(self) -> None:
        if self.kept is not None:
            _unlink_quietly(self.kept)
            self.kept = None


def _undo(done: list, plan: list, exc: OSError) -> str:
    """Put back the files of ``done`` (newest first), drop every kept copy, and say so in
    the one error line of a commit that failed at the first entry of ``plan`` not done."""
    failed = plan[len(done)].dest
    lost = [r.dest for r in reversed(done) if not r.put_back()]
    for r in plan:
        r.forget_kept()
    line = f"{quote(failed)}: cannot write ({exc.strerror})"
    if lost:
        return line + "; already replaced, could not be put back: " + ", ".join(quote(p) for p in lost)
    if done:
        return line + "; no output written (" + ", ".join(quote(r.dest) for r in done) + " restored)"
    return line


def _sync_folder(folder: str) -> None:
    """fsync a folder so the renames in it survive a power cut (best effort: some file
    systems cannot sync a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


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
    temporary files at once, so write errors surface early); put them all in
    place when the block ends normally (:meth:`_Transaction.commit`), discard
    them when it raises, so a failed run leaves no output.  A caller that wants
    to keep the outputs on a particular exception calls ``commit()`` on the
    yielded transaction first; ``tx.done`` tells whether it was committed."""
    global _CURRENT
    if _CURRENT is not None:  # nested: the outer block decides
        yield _CURRENT
        return
    tx = _Transaction()
    _CURRENT = tx
    settle(None)
    try:
        yield tx
        # inside the try: a signal between the block's end and the commit's own guard discards too
        _CURRENT = None
        if tx.done is None:
            tx.commit()
    except BaseException:
        _CURRENT = None
        tx.discard()  # (after a failed commit: nothing left to discard)
        raise


def _unlink_quietly(path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def _write_direct(path: Path, data: bytes) -> None:
    """Write in place (a special file, or a file behind another process's descriptor): never
    created, every byte written."""
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
    removed: list[str] = []
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


def atomic_write(path: str | Path, data: str | bytes, inputs: tuple = (), option: str | None = None,
                 exclusive: bool = False, alone: bool = False) -> None:
    """Write ``data`` to ``path`` so that readers never see a half-written file and a
    failed run leaves nothing behind.

    A new or regular file is written to a staged file in the same folder, synced, and
    renamed over ``path`` (inside :func:`output_transaction`: at the end of the command,
    together with the other outputs); a replaced file's owner, group and mode are kept
    where the caller may set them.  A symlink to a regular file keeps the link; its final
    target is replaced.  A special file (FIFO, device such as /dev/null) or a symlink to
    one is written in place, at commit.  A path naming one of this process's descriptors
    (``/dev/stdout``, ``/dev/fd/N``) is written through it at once, like stdout.  Text is
    written as UTF-8, bytes as they are.  :func:`atomic_stream` does the same for content
    written piece by piece.

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
    exclusive : bool
        ``path`` must not exist: the commit fails rather than replace a file that
        appeared meanwhile (``wormgear new``).
    alone : bool
        Commit this file at once, even inside the run's :func:`output_transaction`
        (a finished part of a resumable run must survive a later failure); still
        staged, synced and renamed, but not undone if the run fails later.

    Raises
    ------
    UsageError
        ``path`` is an input (:func:`refuse_input`), a directory, in a missing
        folder, a file the caller may not write, behind another user's symlink in a
        shared folder, or cannot be written (one line with the system's reason).
    StdoutClosed
        ``path`` is a pipe whose reader went away.
    """
    with atomic_stream(path, inputs, option, exclusive, alone) as write:
        write(data)


@contextmanager
def atomic_stream(path: str | Path, inputs: tuple = (), option: str | None = None, exclusive: bool = False,
                  alone: bool = False):
    """:func:`atomic_write` for content produced piece by piece: yields ``write(chunk)``
    (str or bytes) that appends to the staged file, so a large output is never held in
    memory whole.  The staged file becomes ``path`` when the block ends without an error
    (inside :func:`output_transaction`: at commit); on any error it is removed.  A special
    file is written at commit (its content is held until then); a descriptor at once.
    ``exclusive`` and ``alone`` as for :func:`atomic_write`.  Raises as :func:`atomic_write`.
    """
    path = Path(path)
    kind, dest, fd = _destination(path, option)
    if kind == "descriptor":  # exactly like "-": no input to protect, nothing to stage
        assert fd is not None  # (_destination gives a descriptor's number with it)
        yield _descriptor_writer(path, fd)
        return
    refuse_input(path, inputs, option or "-o")
    if kind == "special":
        pieces: list[bytes] = []
        yield lambda chunk: pieces.append(_as_bytes(chunk))
        blob = b"".join(pieces)
        if _CURRENT is not None and not alone:
            _CURRENT.direct.append((path, blob))
            return
        try:
            _write_direct(path, blob)
        except OSError as exc:
            if exc.errno == errno.EPIPE:
                raise StdoutClosed() from None
            raise UsageError(f"{quote(path)}: cannot write ({exc.strerror})") from None
        return
    tx = _CURRENT if _CURRENT is not None and not alone else _Transaction()  # else: committed at the block's end
    with _staged(path, dest, tx, exclusive) as write:
        yield write
    if tx is not _CURRENT:
        tx.commit(None)


@contextmanager
def _staged(path: Path, dest: Path, tx: _Transaction, exclusive: bool):
    """Stage ``dest``'s new content in its folder (registered in ``tx`` as soon as it exists):
    yields ``write(chunk)``; at the end the file gets the replaced file's owner, group and
    mode, is synced and closed.  On any error it is removed."""
    folder = dest.parent if str(dest.parent) else Path(".")
    _sweep_once(folder)
    tmp = folder / _staged_name(dest)
    try:
        old = None if exclusive else os.stat(dest)
    except OSError:
        old = None
    fd: int | None = None
    try:
        with signals_deferred():  # the staged file is registered as soon as it exists
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
            tx.staged.append((str(tmp), dest, exclusive))
        yield lambda chunk: _write_all(fd, _as_bytes(chunk))
        if old is not None:
            _keep_owner_and_mode(fd, old)
        os.fsync(fd)  # on disk before it is renamed into place (a power cut leaves old or new)
        _fd, fd = fd, None
        os.close(_fd)  # a deferred write error (NFS, quota) surfaces here
    except BaseException as exc:
        if fd is not None:
            try:
                os.close(fd)
            except OSError:
                pass
        with signals_deferred():
            _unlink_quietly(tmp)
            tx.staged = [s for s in tx.staged if s[0] != str(tmp)]
        if isinstance(exc, OSError):
            raise UsageError(f"{quote(path)}: cannot write ({exc.strerror})") from None
        raise


def _keep_owner_and_mode(fd: int, old: os.stat_result) -> None:
    """Give the staged file the owner and group of the file it replaces (as far as the
    caller may: root keeps both, a member of the group keeps the group), then its mode
    (after the owner: a change of owner clears set-id bits)."""
    new = os.fstat(fd)
    if hasattr(os, "fchown") and (new.st_uid, new.st_gid) != (old.st_uid, old.st_gid):
        try:
            os.fchown(fd, old.st_uid, old.st_gid)
        except OSError:
            try:
                os.fchown(fd, -1, old.st_gid)
            except OSError:
                pass
    os.fchmod(fd, stat.S_IMODE(old.st_mode))


# --- what the machine can hold ----------------------------------------------------------
#
# What the machine can hold: sizes checked against the memory a run may use, before the work.
#
# Every command that builds arrays whose size the user chooses (``synth --points x --runs``,
# ``simulate --points``, the sweep's grid, the rows of a measurement file for ``measure`` and
# ``diagnose``) estimates the memory its run will need from those sizes (bytes per row,
# measured by ``bench/bench_limits.py``) and calls :func:`check_memory` first: a run the
# machine cannot hold is one line naming the sizes, the memory they need, what limits it, and
# the options that change it -- never a numpy MemoryError minutes later.
#
# The memory a run may use (:func:`available_memory`) is the least of: the free memory of the
# machine (``MemAvailable`` + free swap), the container's limit (cgroup v2 ``memory.max`` or v1
# ``memory.limit_in_bytes``, less what is used), the process's address-space and data limits
# (``ulimit -v`` / ``-d``, less what is mapped), or what :data:`MEMORY_ENV` says (it replaces
# them all: raise it when an estimate is too cautious, lower it to share a machine).

#: environment variable giving the memory a run may use: bytes, or a number with K, M, G or T
#: (binary: 8G = 8 GiB); it replaces what the machine, container and ulimit say
MEMORY_ENV = "WORMGEAR_MEMORY"

#: the one line of a run that ran out of memory all the same (exit 2)
OUT_OF_MEMORY = ("out of memory: this run needs more than the machine gives it; use a smaller input or "
                 f"fewer points, runs or samples ({MEMORY_ENV} sets the memory a run may use)")

_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def parse_size(text: str) -> int:
    """Bytes of a size written as ``123``, ``512M``, ``8G``, ``1.5T`` (binary units, an
    optional trailing ``B`` or ``iB``).  Raises UsageError naming :data:`MEMORY_ENV`."""
    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([KMGT]?)(?:i?B)?\s*", text, re.I)
    if m is None:
        raise UsageError(f"{MEMORY_ENV}={text!r}: expected a size such as 8G, 512M or a number of bytes")
    return int(float(m.group(1)) * _UNITS[m.group(2).upper()])


def _read_int(path: str) -> int | None:
    try:
        with open(path) as fh:
            text = fh.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _meminfo() -> dict[str, int]:
    out = {}
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                key, _, rest = line.partition(":")
                parts = rest.split()
                if parts and parts[0].isdigit():
                    out[key] = int(parts[0]) * 1024
    except OSError:
        pass
    return out


def _cgroup_room() -> int | None:
    """Bytes the container's memory limit still allows (cgroup v2, then v1), or None."""
    try:
        with open("/proc/self/cgroup") as fh:
            lines = fh.read().splitlines()
    except OSError:
        lines = []
    for line in lines:
        if line.startswith("0::"):
            base = "/sys/fs/cgroup" + line[3:].rstrip("/")
            while True:  # the nearest limit up the tree
                limit = _read_int(base + "/memory.max")
                if limit is not None:
                    used = _read_int(base + "/memory.current") or 0
                    return max(limit - used, 0)
                if base == "/sys/fs/cgroup" or "/" not in base:
                    break
                base = base.rsplit("/", 1)[0]
    limit = _read_int("/sys/fs/cgroup/memory/memory.limit_in_bytes")
    if limit is not None and limit < 1 << 60:
        return max(limit - (_read_int("/sys/fs/cgroup/memory/memory.usage_in_bytes") or 0), 0)
    return None


def _rlimit_room() -> tuple[int, str] | None:
    """Bytes the address-space or data limit (``ulimit -v`` / ``-d``) still allows, or None."""
    try:
        import resource  # lazy: keeps resource off `analyze`'s start-up
    except ImportError:  # pragma: no cover - not POSIX
        return None
    try:
        with open("/proc/self/statm") as fh:
            pages = [int(x) for x in fh.read().split()[:6]]
        mapped, data = pages[0] * os.sysconf("SC_PAGE_SIZE"), pages[5] * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        mapped = data = 0
    best = None
    for name, used, what in (("RLIMIT_AS", mapped, "ulimit -v"), ("RLIMIT_DATA", data, "ulimit -d")):
        limit = getattr(resource, name, None)
        if limit is None:
            continue
        soft = resource.getrlimit(limit)[0]
        if soft != resource.RLIM_INFINITY and soft >= 0:
            room = max(soft - used, 0)
            if best is None or room < best[0]:
                best = (room, f"allowed by {what}")
    return best


def available_memory() -> tuple[int, str]:
    """``(bytes, what limits them)``: the memory this run may still use (module docstring)."""
    env = os.environ.get(MEMORY_ENV)
    if env:
        return parse_size(env), f"set by {MEMORY_ENV}={env.strip()}"
    found = []
    info = _meminfo()
    if "MemAvailable" in info:
        found.append((info["MemAvailable"] + info.get("SwapFree", 0), "free on this machine"))
    else:
        try:
            found.append((os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"), "in this machine"))
        except (OSError, ValueError, AttributeError):  # pragma: no cover - not POSIX
            pass
    room = _cgroup_room()
    if room is not None:
        found.append((room, "left under the container's memory limit"))
    limit = _rlimit_room()
    if limit is not None:
        found.append(limit)
    if not found:  # pragma: no cover - nothing to go by: do not refuse
        return 1 << 62, "unknown"
    return min(found)


def size_text(n: float) -> str:
    """Bytes as people read them: ``1.2 GiB``, ``340 MiB``."""
    for unit, scale in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= scale:
            value = n / scale
            return f"{value:.1f} {unit}" if value < 10 else f"{value:.0f} {unit}"
    return f"{max(n, 0):.0f} bytes"


def check_memory(need: float, what: str, fix: str) -> None:
    """Refuse, before the work, a run that needs more memory than it may use.

    Parameters
    ----------
    need : float
        Estimated peak memory of the run [bytes] (beyond the program itself).
    what : str
        The sizes that make it, as the user gave them (``"--points 10000000 x --runs 20
        (400 million rows)"``).
    fix : str
        What to change (``"lower --points or --runs"``).

    Raises
    ------
    UsageError
        One line: the sizes, the memory they need, the memory available and what limits
        it, the options to change and :data:`MEMORY_ENV`.
    """
    room, source = available_memory()
    if need > room:
        raise UsageError(f"{what}: about {size_text(need)} of memory needed, more than the {size_text(room)} "
                         f"{source}; {fix} (or set "
                         f"{MEMORY_ENV}=SIZE if the machine can give more)")


def count_lines(path, limit: int) -> int | None:
    """Line ends in the first ``limit`` + 1 bytes of a regular file (a fast pass, before the
    file is parsed), or None for anything else (a pipe cannot be read twice) or on error.  A FIFO is
    never opened here: opening and closing it unread would take the writer's data (or kill it with
    SIGPIPE) and leave the parser waiting for a second writer."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb", buffering=0) as fh:
            if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
                return None
            n, left = 0, limit + 1
            while left > 0:
                chunk = fh.read(min(1 << 22, left))
                if not chunk:
                    break
                n += chunk.count(b"\n")
                left -= len(chunk)
            return n
    except OSError:
        return None

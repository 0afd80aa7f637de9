"""File output: atomic writes that never clobber an input."""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

from wormgear_cli.errors import UsageError


def read_text_file(path: str | Path, expected: str, error: type = UsageError, encoding: str = "utf-8") -> str:
    """The text of a user-named input file, or ``error`` with one line saying why not.

    ``expected`` names what the file should be ("a TOML drive file", "a CSV
    file").  Refuses a missing file, a directory, an unreadable, binary (NUL
    bytes) or non-UTF-8 file.
    """
    path = Path(path)
    name = str(path)
    if not path.exists():
        raise error(f"{name}: file not found")
    if path.is_dir():
        raise error(f"{name}: is a directory, expected {expected}")
    try:
        blob = path.read_bytes()
    except OSError as exc:
        raise error(f"{name}: cannot read ({exc.strerror})") from None
    if b"\x00" in blob:
        raise error(f"{name}: binary file, expected {expected}")
    try:
        return blob.decode(encoding)
    except UnicodeDecodeError as exc:
        raise error(f"{name}: not UTF-8 text (byte {exc.start}), expected {expected}") from None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


class _Transaction:
    """Outputs of one command run, written together at the end (all or nothing)."""

    def __init__(self) -> None:
        self.staged: list[tuple[str, Path]] = []  # (temporary file, destination)
        self.direct: list[tuple[Path, str | bytes]] = []  # special files (FIFO, device): written at commit

    def commit(self) -> None:
        try:
            for tmp, dest in self.staged:
                os.replace(tmp, dest)
            for dest, data in self.direct:
                _write_direct(dest, data)
        except OSError as exc:
            self.discard()
            raise UsageError(f"{exc.filename or dest}: cannot write ({exc.strerror})") from None
        self.staged, self.direct = [], []

    def discard(self) -> None:
        for tmp, _ in self.staged:
            _unlink_quietly(tmp)
        self.staged, self.direct = [], []


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


def _open_for(target, data: str | bytes):
    """Open a path or file descriptor for writing ``data``: bytes as they are, text as UTF-8
    with its newlines untouched."""
    if isinstance(data, bytes):
        return open(target, "wb")
    return open(target, "w", encoding="utf-8", newline="")


def _unlink_quietly(path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def _write_direct(path: Path, data: str | bytes) -> None:
    with _open_for(path, data) as fh:
        fh.write(data)


def atomic_write(path: str | Path, data: str | bytes, inputs: tuple = ()) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder
    and a rename, so readers never see a half-written file and a failed run
    leaves nothing behind.  Refuses (UsageError) to overwrite any of
    ``inputs``.  An existing special file (FIFO, device such as /dev/null) is
    written in place instead of being replaced.  Inside
    :func:`output_transaction` the rename waits for the end of the command."""
    path = Path(path)
    for src in inputs:
        if src is not None and (_same_file(path, Path(src)) or path.resolve() == Path(src).resolve()):
            raise UsageError(f"{path}: refusing to overwrite the input file; choose another -o")
    if path.is_dir():
        raise UsageError(f"{path}: is a directory, expected a file name for -o")
    if path.exists() and not path.is_file():
        if _CURRENT is not None:
            _CURRENT.direct.append((path, data))
        else:
            try:
                _write_direct(path, data)
            except OSError as exc:
                raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
        return
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise UsageError(f"{path}: folder {folder} does not exist")
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
        with _open_for(fd, data) as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)
        if _CURRENT is not None:
            _CURRENT.staged.append((tmp, path))
        else:
            os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None:
            _unlink_quietly(tmp)
        if isinstance(exc, OSError):
            raise UsageError(f"{path}: cannot write ({exc.strerror})") from None
        raise

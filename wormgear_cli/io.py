"""File output: atomic writes that never clobber an input."""

from __future__ import annotations

import os
import tempfile
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


def atomic_write(path: str | Path, data: str | bytes, inputs: tuple = ()) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder
    and a rename, so readers never see a half-written file and a failed run
    leaves nothing behind.  Refuses (UsageError) to overwrite any of
    ``inputs``."""
    path = Path(path)
    for src in inputs:
        if src is not None and (_same_file(path, Path(src)) or path.resolve() == Path(src).resolve()):
            raise UsageError(f"{path}: refusing to overwrite the input file; choose another -o")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise UsageError(f"{path}: folder {folder} does not exist")
    if path.is_dir():
        raise UsageError(f"{path}: is a directory, expected a file name for -o")
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, mode, **({} if mode == "wb" else {"encoding": "utf-8", "newline": ""})) as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise

"""File output: atomic writes that never clobber an input."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from wormgear_cli.errors import UsageError


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

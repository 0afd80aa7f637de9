"""Output files: all-or-nothing per command, special files, unwritable paths, odd $COLUMNS."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from tests.support.paths import MCH50
from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_stream, atomic_write, output_transaction


def test_failed_second_output_leaves_no_first_output(runner, tmp_path):
    data = tmp_path / "a.csv"
    missing_folder = tmp_path / "nope" / "t.json"
    r = runner.invoke(app, ["synth", str(MCH50), "-o", str(data), "--truth", str(missing_folder), "--seed", "1"])
    assert r.exit_code == 2
    assert "Traceback" not in r.stderr and "nope" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_transaction_discards_on_error_and_commits_on_success(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    with pytest.raises(RuntimeError):
        with output_transaction():
            atomic_write(a, "x")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with output_transaction():
        atomic_write(a, "x")
        atomic_write(b, b"y")
        assert not a.exists()  # renamed into place only at the end
    assert a.read_text() == "x" and b.read_bytes() == b"y"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]


def test_streamed_output_appears_whole_or_not_at_all(tmp_path):
    out = tmp_path / "big.csv"
    out.write_text("old\n")
    with pytest.raises(RuntimeError):  # fails half-way: the old file stays, no staged file is left
        with atomic_stream(out) as write:
            write("a,b\n")
            write(b"1,2\n")
            raise RuntimeError("boom")
    assert out.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["big.csv"]
    with output_transaction():
        with atomic_stream(out) as write:
            for k in range(3):
                write(f"{k},{k * k}\n")
        assert out.read_text() == "old\n"  # renamed into place only when the command commits
    assert out.read_text() == "0,0\n1,1\n2,4\n" and [p.name for p in tmp_path.iterdir()] == ["big.csv"]


def test_special_files_are_written_in_place_not_replaced(runner, tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_text()))
    reader.start()
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "csv", "-o", str(fifo)])
    reader.join(timeout=10)
    assert r.exit_code == 0
    assert fifo.exists() and not fifo.is_file()  # still a FIFO
    assert received and received[0].startswith("drive,unit,")


def test_unwritable_output_is_a_usage_error(tmp_path, monkeypatch):
    with pytest.raises(UsageError, match="does not exist"):
        atomic_write(tmp_path / "no" / "x.txt", "x")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if os.access(ro, os.W_OK):  # running as root: permissions do not apply, so refuse the write here
            real_open = os.open

            def refuse(path, *args, **kwargs):  # what the kernel says to a non-root user in ro/
                if Path(path).parent == ro:
                    raise PermissionError(13, "Permission denied")
                return real_open(path, *args, **kwargs)

            monkeypatch.setattr(os, "open", refuse)
        with pytest.raises(UsageError, match=r"cannot write \(Permission denied\)"):
            atomic_write(ro / "x.txt", "x")
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o700)


@pytest.mark.parametrize("columns", ["abc", "0", "-5", "5"])
def test_odd_columns_value_still_renders_tables(runner, columns):
    r = runner.invoke(app, ["analyze", str(MCH50)], env={"COLUMNS": columns})
    assert r.exit_code == 0, r.stderr
    assert "transmission error" in r.stdout

"""The shared input reader is bounded: a documented maximum size, binary refused at the first
chunk, endless inputs never read to the end."""

from __future__ import annotations

import os

import pytest

from tests.support.paths import CONFIGS
from wormgear_cli import files as wio
from wormgear_cli.errors import DataError
from wormgear_cli.files import MAX_INPUT_BYTES, read_text_file


def test_a_regular_file_over_the_limit_is_refused_from_its_size_without_reading(tmp_path, monkeypatch):
    path = tmp_path / "big.csv"
    with open(path, "wb") as fh:
        fh.truncate(2 * 1024 * 1024 + 5)  # sparse: size without content
    import io

    reads = []
    real_read = io.FileIO.read

    class Spy(io.FileIO):
        def read(self, n=-1):
            reads.append(n)
            return real_read(self, n)

    monkeypatch.setattr("builtins.open", lambda p, mode, buffering=-1: Spy(p, mode.replace("b", "")))
    with pytest.raises(DataError) as exc:
        read_text_file(path, "a CSV file", DataError, max_bytes=2 * 1024 * 1024)
    assert exc.value.problems == [f"{path}: 2.0 MiB, larger than the 2 MiB accepted; expected a CSV file"]
    assert reads == []  # refused from the size alone


def test_the_default_limit_is_the_documented_constant():
    assert MAX_INPUT_BYTES == 16 * 1024 * 1024
    import inspect

    assert inspect.signature(read_text_file).parameters["max_bytes"].default == MAX_INPUT_BYTES


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_measurement_from_an_endless_device_is_refused_at_once(device):
    if not os.path.exists(device):
        pytest.skip(f"no {device}")
    from wormgear_cli.measurement.readers import read_measurement

    with pytest.raises(DataError) as exc:
        read_measurement(device)
    assert exc.value.problems == [f"{device}: binary file, expected a CSV file"]


def test_binary_is_refused_after_the_first_chunk(tmp_path, monkeypatch):
    import io

    path = tmp_path / "x.csv"
    path.write_bytes(b"angle_deg,error_arcsec\n" + b"\x00" * 10 + b"1,2\n" * (3 * wio._READ_CHUNK))
    reads = []
    real_read = io.FileIO.read

    class Spy(io.FileIO):
        def read(self, n=-1):
            reads.append(n)
            return real_read(self, n)

    monkeypatch.setattr("builtins.open", lambda p, mode, buffering=-1: Spy(p, mode.replace("b", "")))
    with pytest.raises(DataError, match="binary file"):
        read_text_file(path, "a CSV file", DataError)
    assert reads == [wio._READ_CHUNK]  # one chunk of a 12 MiB file


def test_limit_counts_bytes_of_a_pipe(tmp_path):
    fifo = tmp_path / "in.csv"
    os.mkfifo(fifo)
    import threading

    def feed():
        try:
            with open(fifo, "wb") as fh:
                for _ in range(100):
                    fh.write(b"1,2\n" * 1024)
        except BrokenPipeError:  # the reader stopped at the limit
            pass

    t = threading.Thread(target=feed)
    t.start()
    with pytest.raises(DataError, match=r"more than the 65536 bytes accepted"):
        read_text_file(fifo, "a CSV file", DataError, max_bytes=65536)
    t.join(timeout=30)


def test_normal_files_still_read():
    assert read_text_file(CONFIGS / "mch50-warm.csv", "a CSV file").startswith("#")

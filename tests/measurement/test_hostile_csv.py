"""Hostile measurement files stay bounded: endless and binary inputs, huge headers, oversized files.

The bounds are the runner's own limits: each hostile case runs in a subprocess with an address-space
limit (1.5 GB) and a CPU-time limit (60 s); going past either kills it and fails the test.  No timing
assertions.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys

import pytest

from tests.support.paths import ROOT
from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import MAX_FILE_BYTES, ReadOptions
from wormgear_cli.measurement.readers import read_measurement

LIMIT_AS = 1536 * 1024 * 1024
LIMIT_CPU = 60


def _limits():
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_AS, LIMIT_AS))
    resource.setrlimit(resource.RLIMIT_CPU, (LIMIT_CPU, LIMIT_CPU))


def run_measure(*args):
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "wormgear_cli", "measure", *map(str, args)], capture_output=True,
                          text=True, env=env, preexec_fn=_limits, timeout=300)


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_endless_binary_devices_are_refused_at_once(device):
    if not os.path.exists(device):
        pytest.skip(f"no {device}")
    result = run_measure(device)
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == f"error: {device}: binary file, expected a CSV file\n"


def test_eighty_thousand_columns_are_read_within_bounds(tmp_path):
    path = tmp_path / "wide.csv"
    extra = [f"c{i}" for i in range(80_000)]
    with open(path, "w") as fh:
        fh.write(",".join(["angle_deg", "error_arcsec", *extra]) + "\n")
        for r in range(3):
            fh.write(",".join([str(100 * r), str(r + 1)] + ["0"] * len(extra)) + "\n")
    result = run_measure(path, "-f", "json", "--orders", "1")
    assert result.returncode == 0, result.stderr
    assert '"rows": 3' in result.stdout


def test_a_canonical_column_twice_in_a_wide_header_is_named(tmp_path):
    path = tmp_path / "dup.csv"
    extra = [f"c{i}" for i in range(50_000)]
    path.write_text(",".join(["angle_deg", "error_arcsec", *extra, "angle_deg"]) + "\n" +
                    ",".join(["0", "1", *["0"] * len(extra), "0"]) + "\n")
    result = run_measure(path)
    assert result.returncode == 2
    assert result.stderr == f"error: {path}:1: column angle_deg appears twice\n"


def test_file_larger_than_the_limit_is_refused(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("angle_deg,error_arcsec\n" + "1,2\n" * 1000)
    with pytest.raises(DataError) as info:
        read_measurement(path, options=ReadOptions(max_bytes=2048))
    assert info.value.problems == [f"{path}: 4023 bytes, larger than the 2048 bytes accepted; expected a CSV file"]
    assert MAX_FILE_BYTES == 256 * 1024 * 1024  # the documented limit (docs/commands/measure.md, Limits)


def test_binary_after_a_text_start_and_bad_utf8(tmp_path):
    path = tmp_path / "b.csv"
    path.write_bytes(b"angle_deg,error_arcsec\n0,1\n" + b"\xff\xfe\x00\x01" * 10)
    with pytest.raises(DataError) as info:
        read_measurement(path)
    assert info.value.problems == [f"{path}: binary file, expected a CSV file"]
    path.write_bytes(b"angle_deg,error_arcsec\n0,1\n10,\xe9\n")  # Latin-1 text: says where
    with pytest.raises(DataError) as info:
        read_measurement(path)
    assert info.value.problems == [f"{path}: not UTF-8 text (byte 30), expected a CSV file"]


@pytest.mark.parametrize("cell,delim,expected", [
    ("1" * 140_000, ",", "column error_arcsec: expected a finite number, got '{}'... (140000 characters)"
     .format("1" * 40)),
    ("x" * 140_000, ";", "column error_arcsec: expected a number, got '{}'... (140000 characters)".format("x" * 40)),
])
def test_a_cell_over_the_csv_modules_limit_is_one_clipped_error_line(tmp_path, cell, delim, expected):
    # the csv module's own field limit (128 KiB) must not surface as a traceback; the message is cut
    path = tmp_path / "long.csv"
    rows = ["angle_deg,error_arcsec", "0,1", f"15,{cell}", "30,2"]
    path.write_text("\n".join(r.replace(",", delim) for r in rows) + "\n")
    with pytest.raises(DataError) as err:
        read_measurement(path)
    assert err.value.problems == [f"{path}:3: {expected}"]
    import csv

    assert csv.field_size_limit() == 131072  # the process-wide limit is restored


def test_a_header_cell_over_the_limit_is_clipped_in_the_message(tmp_path):
    path = tmp_path / "long.csv"
    path.write_text("angle_deg,error_arcsec" + "y" * 140_000 + "\n0,1\n")
    with pytest.raises(DataError) as err:
        read_measurement(path)
    (line,) = err.value.problems
    assert "error_arcsec" + "y" * 28 + "... (140012 characters)" in line and len(line) < 300

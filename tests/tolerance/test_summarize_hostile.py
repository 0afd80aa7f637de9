"""--summarize reads a file the user names: a directory, an endless or binary file, and a file
that turns binary after valid rows are one-line errors (exit 2), read within a bounded size."""

from __future__ import annotations

import pytest

from wormgear_cli.cli import app
from tests.conftest import MCH50

ARGS = ["tolerance", str(MCH50), "--samples", "20", "--metrics", "paper"]


@pytest.fixture
def samples_csv(runner, tmp_path):
    r = runner.invoke(app, [*ARGS, "--format", "csv"])
    assert r.exit_code == 0
    path = tmp_path / "s.csv"
    path.write_text(r.stdout)
    return path


def _summarize(runner, path):
    return runner.invoke(app, [*ARGS, "--summarize", str(path)])


def test_a_directory_is_named_as_one(runner, tmp_path):
    r = _summarize(runner, tmp_path)
    assert r.exit_code == 2
    assert r.stderr == f"error: {tmp_path}: is a directory, expected a samples CSV of wormgear tolerance --format csv\n"


def test_an_endless_file_stops_at_the_line_bound(runner):
    r = _summarize(runner, "/dev/zero")
    assert r.exit_code == 2 and r.stderr.startswith("error: /dev/zero: line 1: binary") and len(r.stderr.splitlines()) == 1


def test_zeros_after_valid_rows(runner, samples_csv):
    n_lines = len(samples_csv.read_text().splitlines())
    with open(samples_csv, "ab") as fh:
        fh.write(b"\0" * 200_000)
    r = _summarize(runner, samples_csv)
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {samples_csv}: line {n_lines + 1}: binary or longer than")


def test_bad_utf8_after_valid_rows(runner, samples_csv):
    with open(samples_csv, "ab") as fh:
        fh.write(b"\xff\xfe\n")
    r = _summarize(runner, samples_csv)
    assert r.exit_code == 2 and "not UTF-8 text" in r.stderr and len(r.stderr.splitlines()) == 1


def test_the_valid_file_still_summarizes(runner, samples_csv):
    assert _summarize(runner, samples_csv).exit_code == 0

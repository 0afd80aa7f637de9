"""--summarize reads a file the user names: a directory, an endless or binary file, and a file
that turns binary after valid rows are one-line errors (exit 2), read within a bounded size."""

from __future__ import annotations

import pytest

from tests.support.paths import MCH50
from wormgear_cli.cli import app

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


def test_an_endless_device_or_a_pipe_is_refused_at_once(runner):
    # not a regular file: it could not be read twice (header, then samples), and /dev/zero never ends
    r = _summarize(runner, "/dev/zero")
    assert r.exit_code == 2 and len(r.stderr.splitlines()) == 1
    assert r.stderr.startswith("error: /dev/zero: not a regular file, expected a samples CSV")


def test_a_first_line_without_an_end_stops_at_the_line_bound(runner, tmp_path):
    path = tmp_path / "zeros.csv"
    path.write_bytes(b"\0" * 200_000)
    r = _summarize(runner, path)
    assert r.exit_code == 2 and r.stderr.startswith(f"error: {path}: line 1: binary") and len(r.stderr.splitlines()) == 1


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


def _parts(runner, tmp_path, n=400, k=4):
    parts = []
    for i in range(1, k + 1):
        r = runner.invoke(app, [*ARGS[:2], "--samples", str(n), "--metrics", "paper", "--format", "csv",
                                "--shard", f"{i}/{k}"])
        assert r.exit_code == 0
        parts.append(r.stdout.splitlines(keepends=True))
    return parts


def _joined(path, parts):
    path.write_text("".join(parts[0][:1] + [line for p in parts for line in p[1:]]))
    return path


def test_a_missing_last_or_first_part_is_refused(runner, tmp_path):
    parts = _parts(runner, tmp_path)
    args = [*ARGS[:2], "--samples", "400", "--metrics", "paper", "--summarize"]
    r = runner.invoke(app, [*args, str(_joined(tmp_path / "three.csv", parts[:3]))])
    assert r.exit_code == 2 and "300 samples (0 to 299), expected 400" in r.stderr
    r = runner.invoke(app, [*args, str(_joined(tmp_path / "nofirst.csv", parts[1:]))])
    assert r.exit_code == 2 and "the samples start at 100, expected 0" in r.stderr
    assert runner.invoke(app, [*args, str(_joined(tmp_path / "all.csv", parts))]).exit_code == 0


@pytest.mark.parametrize("bad", ["nan", "inf", "1e400"])
def test_a_non_finite_number_names_its_line_and_column(runner, samples_csv, bad):
    lines = samples_csv.read_text().splitlines()
    cells = lines[2].split(",")
    cells[-1] = bad
    lines[2] = ",".join(cells)
    samples_csv.write_text("\n".join(lines) + "\n")
    r = _summarize(runner, samples_csv)
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {samples_csv}: line 3: total_backlash: expected a finite number")


def test_a_byte_order_mark_is_tolerated(runner, samples_csv):
    samples_csv.write_bytes(b"\xef\xbb\xbf" + samples_csv.read_bytes())
    assert _summarize(runner, samples_csv).exit_code == 0


def test_an_enormous_cell_is_clipped_in_the_message(runner, samples_csv):
    header = samples_csv.read_text().splitlines()[0]
    samples_csv.write_text(header + "\n" + "1" * 60_000 + "\n")
    r = _summarize(runner, samples_csv)
    assert r.exit_code == 2 and len(r.stderr) < 400

"""Issue 23, item 1: a path naming one of the process's descriptors (/dev/stdout, /dev/fd/N,
/proc/self/fd/N) is written through that descriptor, exactly like ``-``: appending where the
descriptor appends, never renamed over what it points at."""

from __future__ import annotations

import os

import pytest

from tests.support.paths import MCH50
from tests.support.processes import shell

pytestmark = pytest.mark.skipif(not os.path.exists("/dev/fd/1"), reason="needs /dev/fd")

CSV_HEAD = b"drive,unit,"


def test_dev_stdout_appended_to_a_file_keeps_what_was_there(tmp_path):
    """The issue's command: ``echo KEEP > log.txt; wormgear ... -o /dev/stdout >> log.txt``."""
    r = shell(f"echo KEEP > log.txt; wormgear analyze {MCH50} -f csv -o /dev/stdout >> log.txt", tmp_path)
    assert r.returncode == 0, r.stderr.decode()
    log = (tmp_path / "log.txt").read_bytes()
    assert log.startswith(b"KEEP\n" + CSV_HEAD) and log.count(b"\n") == 3
    assert r.stderr == b""  # written like -: no "wrote /dev/stdout"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.txt"]


def test_dev_stdout_inside_a_grouped_redirect_keeps_the_order(tmp_path):
    """``{ echo H; wormgear ... -o /dev/stdout; echo F; } > r.txt``: H, the result, F, in that order."""
    r = shell(f"{{ echo H; wormgear analyze {MCH50} -f csv -o /dev/stdout; echo F; }} > r.txt", tmp_path)
    assert r.returncode == 0, r.stderr.decode()
    lines = (tmp_path / "r.txt").read_bytes().split(b"\n")
    assert lines[0] == b"H" and lines[1].startswith(CSV_HEAD) and lines[3] == b"F" and lines[4] == b""


def test_another_descriptor_by_number_appends_too(tmp_path):
    """A variant: the data of synth through /dev/fd/3 opened for appending, the truth as a file."""
    r = shell(f"echo '# kept' > data.csv; wormgear synth {MCH50} --seed 1 -o /dev/fd/3 --truth t.json 3>>data.csv",
              tmp_path)
    assert r.returncode == 0, r.stderr.decode()
    data = (tmp_path / "data.csv").read_text()
    assert data.startswith("# kept\n#") and "angle_deg,error_arcsec" in data
    assert r.stderr.decode() == "wrote t.json\n"  # the file is announced, the descriptor is not
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data.csv", "t.json"]


@pytest.mark.skipif(not os.path.exists("/proc/self/fd/1"), reason="needs /proc")
def test_proc_self_fd_is_written_in_place_not_over_the_redirect_target(tmp_path):
    """A variant through /proc/self/fd/1, stdout truncated by '>': the result lands where the
    descriptor stands, and the redirect target keeps its inode (it was not renamed over)."""
    r = shell(f"echo old > out.csv; ls -i out.csv; wormgear simulate {MCH50} --points 10 -o /proc/self/fd/1 "
              "> out.csv; ls -i out.csv >&2", tmp_path)
    assert r.returncode == 0, r.stderr.decode()
    out = (tmp_path / "out.csv").read_text()
    assert out.startswith("angle_deg,") and len(out.splitlines()) == 11
    assert r.stderr == r.stdout  # the same inode before and after: written through, not replaced


def test_a_descriptor_that_is_not_open_is_one_error_line(tmp_path):
    r = shell(f"wormgear analyze {MCH50} -f csv -o /dev/fd/7", tmp_path)
    assert r.returncode == 2
    assert r.stderr.decode() == "error: /dev/fd/7: cannot write (Bad file descriptor)\n"
    assert list(tmp_path.iterdir()) == []

"""Output paths that are not plain files: special files and symlinks are decided from what the
path is (lstat) and what a link points at (stat); never renamed over."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_write, check_output_path, output_transaction, refuse_input


def test_symlink_to_a_device_is_written_through_not_replaced(tmp_path, runner):
    link = tmp_path / "sink"
    link.symlink_to(os.devnull)
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "csv", "-o", str(link)])
    assert r.exit_code == 0, r.stderr
    assert link.is_symlink() and os.readlink(link) == os.devnull
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sink"]


def test_symlink_to_a_fifo_is_written_in_place(tmp_path, runner):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    link = tmp_path / "link"
    link.symlink_to(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "csv", "-o", str(link)])
    reader.join(timeout=60)
    assert r.exit_code == 0, r.stderr
    assert link.is_symlink() and got and got[0].startswith(b"drive,unit,")


def test_symlink_to_a_regular_file_keeps_the_link_and_replaces_its_target(tmp_path):
    target = tmp_path / "runs" / "result.csv"
    target.parent.mkdir()
    target.write_text("old\n")
    target.chmod(0o640)
    link = tmp_path / "result.csv"
    link.symlink_to(target)
    atomic_write(link, "new\n")
    assert link.is_symlink() and target.read_text() == "new\n"
    assert oct(target.stat().st_mode & 0o777) == oct(0o640)  # the replaced file keeps its permissions
    assert sorted(p.name for p in target.parent.iterdir()) == ["result.csv"]


def test_dangling_symlink_creates_its_target(tmp_path):
    link = tmp_path / "out.csv"
    link.symlink_to(tmp_path / "real.csv")
    atomic_write(link, "x\n")
    assert link.is_symlink() and (tmp_path / "real.csv").read_text() == "x\n"


def test_dev_stdout_redirected_to_a_file(tmp_path):
    """``-o /dev/stdout > file``: the redirect gets the result and /dev/stdout stays a link.  A link
    of our own to /proc/self/fd/1 stands in for /dev/stdout (this test runs as any user and must
    not be able to replace the real one if the behaviour regressed)."""
    if not os.path.exists("/proc/self/fd/1"):
        pytest.skip("needs /proc/self/fd")
    link = tmp_path / "stdout"
    link.symlink_to("/proc/self/fd/1")
    out = tmp_path / "redirect.csv"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with open(out, "wb") as fh:
        r = subprocess.run([sys.executable, "-m", "wormgear_cli", "analyze", str(MCH50), "-f", "csv", "-o", str(link)],
                           stdout=fh, stderr=subprocess.PIPE, env=env, timeout=120)
    assert r.returncode == 0, r.stderr.decode()
    assert link.is_symlink() and os.readlink(link) == "/proc/self/fd/1"
    assert out.read_text().startswith("drive,unit,")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["redirect.csv", "stdout"]
    if os.path.islink("/dev/stdout"):
        assert os.readlink("/dev/stdout").startswith("/proc/")


@pytest.mark.parametrize("make", ["dir", "link_to_dir"])
def test_output_naming_a_directory_is_one_error_line(tmp_path, runner, make):
    d = tmp_path / "d"
    d.mkdir()
    target = d
    if make == "link_to_dir":
        target = tmp_path / "l"
        target.symlink_to(d)
    r = runner.invoke(app, ["analyze", str(MCH50), "-o", str(target)])
    assert r.exit_code == 2
    assert r.stderr == f"error: {target}: is a directory, expected a file name for -o\n"


@pytest.mark.parametrize("exists", [True, False])
def test_output_ending_with_a_slash_names_a_folder_and_writes_nothing(tmp_path, runner, exists):
    """``-o out/``: a folder, whether or not it exists (the path object drops the slash: it had
    written a file named ``out``)."""
    target = tmp_path / "out"
    if exists:
        target.mkdir()
    r = runner.invoke(app, ["analyze", str(MCH50), "-o", f"{target}/"])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {target}/: ends with /, which names a folder; expected a file name for -o "
                        f"(e.g. {target}/result.json)\n")
    assert target.is_dir() == exists and not (target.exists() and not exists)
    assert list(tmp_path.iterdir()) == ([target] if exists else [])


@pytest.mark.parametrize("args", [["analyze", str(MCH50), "-o", ""], ["new", ""]])
def test_an_empty_output_name_is_refused_as_empty(tmp_path, runner, monkeypatch, args):
    """``-o ''`` (an unset shell variable): pathlib reads it as "." and the message had named the
    current folder."""
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, args)
    assert r.exit_code == 2 and r.stdout == "" and list(tmp_path.iterdir()) == []
    assert r.stderr.startswith(f"error: {'-o' if args[0] == 'analyze' else 'NEW.toml'}: the file name is empty; "
                               "expected a file name (e.g. ")


def test_output_in_a_missing_folder_is_refused_before_any_work(tmp_path):
    with pytest.raises(UsageError, match=r"folder .*nope does not exist for -o$"):
        check_output_path(tmp_path / "nope" / "x.csv")


def test_input_through_a_symlink_or_hard_link_is_never_overwritten(tmp_path, runner):
    spec = tmp_path / "drive.toml"
    spec.write_bytes(MCH50.read_bytes())
    (tmp_path / "alias.toml").symlink_to(spec)
    os.link(spec, tmp_path / "hard.toml")
    for name in ("alias.toml", "hard.toml", "drive.toml"):
        r = runner.invoke(app, ["analyze", str(spec), "-f", "json", "-o", str(tmp_path / name)])
        assert r.exit_code == 2, name
        assert r.stderr == f"error: {tmp_path / name}: refusing to overwrite the input file; choose another -o\n"
    assert spec.read_bytes() == MCH50.read_bytes()


def test_plot_onto_an_input_is_refused_by_the_one_check(tmp_path, runner):
    spec = tmp_path / "drive.png"  # a drive file named like a plot
    spec.write_bytes(MCH50.read_bytes())
    r = runner.invoke(app, ["simulate", str(spec), "--points", "100", "--plot", str(spec)])
    assert r.exit_code == 2
    assert r.stderr == f"error: {spec}: refusing to overwrite the input file; choose another --plot\n"


def test_files_read_in_a_run_are_protected_without_being_named(tmp_path):
    from wormgear_cli.files import read_text_file

    f = tmp_path / "in.txt"
    f.write_text("data\n")
    with pytest.raises(UsageError, match="refusing to overwrite the input file"):
        with output_transaction():
            read_text_file(f, "a text file")
            refuse_input(f, (), "-o")
    assert f.read_text() == "data\n"


def test_special_input_and_output_on_one_device_are_allowed(tmp_path):
    refuse_input(os.devnull, [os.devnull], "-o")  # e.g. /dev/stdin and /dev/stdout on one terminal


def test_long_output_name_still_stages(tmp_path):
    name = "r" * 250 + ".csv"  # the staged name must stay within NAME_MAX
    atomic_write(tmp_path / name, "x")
    assert [p.name for p in tmp_path.iterdir()] == [name]


@pytest.mark.parametrize("args", [
    ["simulate", str(MCH50), "--points", "100", "--plot", "{d}.png"],
    ["synth", str(MCH50), "--seed", "1", "-o", "{tmp}/x.csv", "--truth", "{d}"],
    ["new", "{d}/"],
])
def test_every_output_option_naming_a_directory_is_one_error_line(tmp_path, runner, args):
    d = tmp_path / "d"
    d.mkdir()
    (tmp_path / "d.png").mkdir()
    args = [a.format(d=d, tmp=tmp_path) for a in args]
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: ") and "Usage" not in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "d.png"]


def test_a_plot_path_in_a_missing_folder_is_refused_before_any_work(tmp_path, runner, monkeypatch):
    # the sampling must not start: --plot is checked up front like -o
    from wormgear_cli.tolerance import engine

    def no_work(*args, **kwargs):
        raise AssertionError("the samples were drawn before --plot was checked")

    monkeypatch.setattr(engine, "run", no_work)
    plot = tmp_path / "missing" / "p.png"
    r = runner.invoke(app, ["tolerance", str(MCH50), "-n", "1000", "--plot", str(plot)])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {plot}") and len(r.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("ending", ["/", "/.", "/..", "/./"])
@pytest.mark.parametrize(("args", "option", "example"), [
    (["analyze", str(MCH50), "-o"], "-o", "result.json"),
    (["sweep", str(MCH50), "--i", "8:10:2", "--l-mm", "40:50:2", "-f", "csv", "--shard", "1/2", "-o"], "-o",
     "result.json"),
    (["synth", str(MCH50), "--truth"], "--truth", "truth.json"),
    (["simulate", str(MCH50), "--plot"], "--plot", "plot.png"),
    (["tolerance", str(MCH50), "--plot"], "--plot", "plot.png"),
    (["sweep", str(MCH50), "--i", "8:10:2", "--l-mm", "40:50:2", "--plot"], "--plot", "plot.png"),
    (["measure", str(CONFIGS / "mch50-warm.csv"), "--plot"], "--plot", "plot.png"),
    (["compensate", str(CONFIGS / "mch50-warm.csv"), "-f", "csv", "--report"], "--report", "report.json"),
    (["diagnose", str(MCH50), str(CONFIGS / "mch50-warm.csv"), "--write-spec"], "--write-spec", "drive.toml"),
    (["diagnose", str(MCH50), str(CONFIGS / "mch50-warm.csv"), "--plot"], "--plot", "plot.png"),
    (["new"], "NEW.toml", "drive.toml"),
])
def test_every_output_path_ending_in_a_folder_is_refused_by_its_raw_text(tmp_path, runner, monkeypatch, args,
                                                                         option, example, ending):
    """``out/``, ``out/.``, ``out/..``: a folder, whatever the option (pathlib drops "/" and "/.": each
    had written a file named ``out``, and a shard its manifest too)."""
    monkeypatch.chdir(tmp_path)
    folder = "out/../" if ending == "/.." else "out/"
    r = runner.invoke(app, [*args, "out.toml" + ending if option == "NEW.toml" else "out" + ending])
    if option == "NEW.toml":
        folder = folder.replace("out", "out.toml")
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {folder.removesuffix('/').removesuffix('/..')}{ending}: ends with {ending}, which "
                        f"names a folder; expected a file name for {option} (e.g. {folder}{example})\n")
    assert list(tmp_path.iterdir()) == []

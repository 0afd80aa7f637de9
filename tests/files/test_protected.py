"""Issue 23, items 2 and 6: no one else's files.

* Item 2: an output path that goes through a symlink of another user in a sticky
  world-writable folder (/tmp) is refused, as the kernel's ``protected_symlinks`` refuses to
  follow it on open (a rename would otherwise replace the link's target with root's output).
* Item 6: a file the caller could not write with a shell's ``>`` (its own ``chmod 444`` file)
  is refused; a replaced file keeps its owner, group and mode where the caller may set them.

Real users: files owned by ``nobody`` (uid 65534), and the command run as ``nobody`` in a
forked child.  These tests need root and are skipped otherwise.
"""

from __future__ import annotations

import os
import shutil
import stat

import pytest
from typer.testing import CliRunner

from tests.support.paths import MCH50
from tests.support.processes import NOBODY, as_user, needs_root, open_folder, run
from wormgear_cli.cli import app

pytestmark = needs_root


@pytest.fixture
def shared():
    """A sticky world-writable folder owned by root, as /tmp."""
    folder = open_folder(0o1777)
    yield folder
    shutil.rmtree(folder)


@pytest.fixture
def private():
    """A folder of root's, readable by all (its files may belong to others)."""
    folder = open_folder(0o755)
    yield folder
    shutil.rmtree(folder)


def _victim(folder, text="root's data\n"):
    victim = folder / "victim.conf"
    victim.write_text(text)
    return victim


def test_another_users_symlink_in_a_shared_folder_is_not_followed(shared, private):
    """The issue's case: nobody plants /tmp/out.csv -> root's file; root's -o must not replace it."""
    victim = _victim(private)
    link = shared / "out.csv"
    link.symlink_to(victim)
    os.lchown(link, NOBODY, NOBODY)
    r = run(["analyze", MCH50, "-f", "csv", "-o", link], shared)
    err = r.stderr.decode()
    assert r.returncode == 2, err
    assert err == (f"error: {link}: not following {link}, a symlink of another user (uid {NOBODY}) in the shared "
                   f"folder {shared}; choose another -o\n")
    assert victim.read_text() == "root's data\n" and link.is_symlink()
    assert sorted(p.name for p in shared.iterdir()) == ["out.csv"] and sorted(p.name for p in private.iterdir()) == [
        "victim.conf"]


def test_another_users_symlink_as_a_folder_of_the_path_is_not_followed(shared, private):
    """A variant: the planted link is a folder on the way (--plot /tmp/d/p.png, d -> root's folder)."""
    link = shared / "d"
    link.symlink_to(private)
    os.lchown(link, NOBODY, NOBODY)
    r = run(["simulate", MCH50, "--points", "10", "--plot", link / "p.png", "-o", os.devnull], shared)
    assert r.returncode == 2
    assert r.stderr.decode().startswith(f"error: {link / 'p.png'}: not following {link}, a symlink of another user")
    assert list(private.iterdir()) == []


def test_a_symlink_of_the_folders_owner_is_followed(private):
    """What the kernel allows stays allowed: in nobody's own sticky folder, nobody's link is followed."""
    theirs = open_folder(0o1777, owner=NOBODY)
    try:
        target = private / "result.csv"
        link = theirs / "out.csv"
        link.symlink_to(target)
        os.lchown(link, NOBODY, NOBODY)
        r = run(["analyze", MCH50, "-f", "csv", "-o", link], private)
        assert r.returncode == 0, r.stderr.decode()
        assert target.read_text().startswith("drive,unit,") and link.is_symlink()
    finally:
        shutil.rmtree(theirs)


def test_another_users_file_in_a_shared_folder_is_not_replaced(shared):
    """protected_regular: nobody's file in root's sticky folder is not root's to replace."""
    theirs = shared / "report.csv"
    theirs.write_text("theirs\n")
    os.chown(theirs, NOBODY, NOBODY)
    r = run(["analyze", MCH50, "-f", "csv", "-o", theirs], shared)
    assert r.returncode == 2
    assert r.stderr.decode() == (f"error: {theirs}: a file of another user (uid {NOBODY}) in the shared folder "
                                 f"{shared}; not replaced, choose another -o\n")
    assert theirs.read_text() == "theirs\n"


def _run_as_caller(args):
    """In the child (as nobody): what a shell's ``>`` says, then the command's exit code and stderr."""
    target = args[args.index("-o") + 1]
    try:
        with open(target, "a"):
            shell_may_write = True
    except PermissionError:
        shell_may_write = False
    r = CliRunner().invoke(app, [str(a) for a in args])
    return shell_may_write, r.exit_code, r.stderr


def test_a_users_own_read_only_file_is_refused_as_by_the_shell():
    """The issue's case: nobody's own chmod 444 file; '>' is refused, so -o is too."""
    CliRunner().invoke(app, ["analyze", str(MCH50), "-f", "csv"])  # load what the child needs, as root
    home = open_folder(0o755, owner=NOBODY)
    try:
        mine = home / "result.csv"
        mine.write_text("kept\n")
        os.chown(mine, NOBODY, NOBODY)
        mine.chmod(0o444)
        shell_may_write, code, err = as_user(NOBODY, _run_as_caller, ["analyze", MCH50, "-f", "csv", "-o", mine])
        assert not shell_may_write
        assert code == 2
        assert err == (f"error: {mine}: cannot write (Permission denied); the file is read-only for you (mode 444): "
                       "make it writable or choose another -o\n")
        assert mine.read_text() == "kept\n" and sorted(p.name for p in home.iterdir()) == ["result.csv"]
    finally:
        shutil.rmtree(home)


def test_a_users_own_writable_file_is_replaced_keeping_its_mode():
    """The check refuses no more than the shell: nobody's own 0640 file is replaced, mode kept."""
    CliRunner().invoke(app, ["analyze", str(MCH50), "-f", "csv"])
    home = open_folder(0o755, owner=NOBODY)
    try:
        mine = home / "result.csv"
        mine.write_text("old\n")
        os.chown(mine, NOBODY, NOBODY)
        mine.chmod(0o640)
        shell_may_write, code, err = as_user(NOBODY, _run_as_caller, ["analyze", MCH50, "-f", "csv", "-o", mine])
        assert shell_may_write and code == 0, err
        st = mine.stat()
        assert mine.read_text().startswith("drive,unit,") and stat.S_IMODE(st.st_mode) == 0o640
        assert (st.st_uid, st.st_gid) == (NOBODY, NOBODY)
    finally:
        shutil.rmtree(home)


def test_root_replacing_another_users_file_keeps_its_owner_group_and_mode(private):
    """The issue's case: root's -o over nobody's file left it root:root, nobody locked out."""
    theirs = private / "report.csv"
    theirs.write_text("theirs\n")
    os.chown(theirs, NOBODY, NOBODY)
    theirs.chmod(0o604)
    r = run(["analyze", MCH50, "-f", "csv", "-o", theirs], private)
    assert r.returncode == 0, r.stderr.decode()
    st = theirs.stat()
    assert theirs.read_text().startswith("drive,unit,")
    assert (st.st_uid, st.st_gid, stat.S_IMODE(st.st_mode)) == (NOBODY, NOBODY, 0o604)
    assert sorted(p.name for p in private.iterdir()) == ["report.csv"]


def test_root_replacing_a_file_through_a_link_keeps_the_targets_owner(private):
    """A variant: the file is reached through a (root's) symlink, and it is a plot."""
    pytest.importorskip("matplotlib")
    target = private / "plots" / "p.png"
    target.parent.mkdir()
    target.write_bytes(b"old")
    os.chown(target, NOBODY, 0)
    target.chmod(0o664)
    link = private / "p.png"
    link.symlink_to(target)
    r = run(["simulate", MCH50, "--points", "20", "--plot", link, "-o", os.devnull], private)
    assert r.returncode == 0, r.stderr.decode()
    st = target.stat()
    assert target.read_bytes().startswith(b"\x89PNG") and link.is_symlink()
    assert (st.st_uid, st.st_gid, stat.S_IMODE(st.st_mode)) == (NOBODY, 0, 0o664)

"""What every command shares (:mod:`wormgear_cli.cli.common`): tables that fit 80 columns
without cutting a number, no escape codes under NO_COLOR, one way of announcing written
files, one path to stdout."""

from __future__ import annotations

import re
from collections import Counter

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.examples import examples
from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app, common

NUMBER = re.compile(r"-?\d+\.\d+(?:e[-+]?\d+)?")

TABLE_COMMANDS = {
    "sweep i,l": ["sweep", str(MCH50), "--i", "2:10:9", "--l-mm", "100:300:11"],
    "sweep module": ["sweep", str(MCH50), "--i", "2:10:5", "--l-mm", "100:300:5", "--module-mm", "2.5"],
    "sweep param": ["sweep", str(MCH50), "--param", "worm_pair.lead_error_mm=0:0.05:3",
                    "--param", "assembly.gear_centre_distance_error_mm=0.01:0.03:2"],
    "sweep deg": ["sweep", str(MCH50), "--i", "2:10:9", "--l-mm", "100:300:11", "--unit", "urad"],
    "analyze": ["analyze", str(MCH50)],
}


@pytest.mark.parametrize("name", TABLE_COMMANDS)
def test_tables_fit_80_columns_without_cutting_a_number(runner, name):
    narrow = runner.invoke(app, TABLE_COMMANDS[name], env={"COLUMNS": "80"})
    wide = runner.invoke(app, TABLE_COMMANDS[name], env={"COLUMNS": "250"})
    assert narrow.exit_code == 0 and wide.exit_code == 0
    assert "…" not in narrow.stdout
    assert max(len(line) for line in narrow.stdout.splitlines()) <= 80
    # every number of the wide rendering appears whole in the narrow one
    missing = Counter(NUMBER.findall(wide.stdout)) - Counter(NUMBER.findall(narrow.stdout))
    assert not missing


def test_the_heat_map_that_was_cut_at_80_columns_is_split_instead(runner):
    r = runner.invoke(app, TABLE_COMMANDS["sweep i,l"], env={"COLUMNS": "80"})
    assert "107.61" in r.stdout  # the total TE at i = 2, l = 300 mm (a 6-character number, cut to 7 before)
    assert "(continued)" in r.stdout


def test_fit_table_splits_only_when_the_numbers_do_not_fit():
    from rich.console import Console
    from rich.table import Table

    def make():
        t = Table(title="wide")
        t.add_column("row")
        for c in range(12):
            t.add_column(f"c{c}", justify="right")
        for r in range(3):
            t.add_row(f"r{r}", *(f"{123456.789 * (r + 1) + c:.3f}" for c in range(12)))
        return t

    for width, n_parts in ((250, 1), (60, None)):
        console = Console(width=width, color_system=None, record=True, file=open("/dev/null", "w"))
        parts = common.fit_table(make(), console, width)
        if n_parts is not None:
            assert len(parts) == n_parts
        else:
            assert len(parts) > 1
        for p in parts:
            console.print(p)
        text = console.export_text()
        assert max(len(line) for line in text.splitlines()) <= width and "…" not in text
        for r in range(3):
            for c in range(12):
                assert f"{123456.789 * (r + 1) + c:.3f}" in text


@settings(max_examples=examples(60), deadline=None)
@given(cells=st.lists(st.lists(st.sampled_from(["1.5", "-12.25", "123456.789", "arcsec", "a b c", "worm wheel",
                                                "x" * 14, "0"]), min_size=3, max_size=3), min_size=1, max_size=4),
       header=st.sampled_from(["row", "total transmission error", "F_pT"]), width=st.integers(20, 100))
def test_a_table_said_to_fit_draws_whole_and_one_said_not_to_would_cut(cells, header, width):
    """fit_table's test (measured at its natural width first, drawn only when it may wrap) against
    rich's own drawing at that width: True exactly when no line is longer than the width and every
    word of the cells comes out whole."""
    from io import StringIO

    from rich.console import Console
    from rich.table import Table

    table = Table()
    for name in (header, "b", "c"):
        table.add_column(name, overflow="fold", no_wrap=False)
    for row in cells:
        table.add_row(*row)
    out = StringIO()
    Console(file=out, width=width, no_color=True, color_system=None, highlight=False, force_terminal=False,
            soft_wrap=False, legacy_windows=False).print(table)
    drawn = out.getvalue()
    words = Counter(w for row in [[header, "b", "c"], *cells] for cell in row for w in cell.split())
    whole = (all(len(line.rstrip()) <= width for line in drawn.splitlines())
             and not words - Counter(re.sub("[\u2500-\u257f]", " ", drawn).split()))
    assert common._fits(table, None, width) == whole


def test_a_table_of_numbers_fits_from_its_drawn_width_on_and_not_one_column_less():
    """Numbers cannot wrap at a space: the table fits exactly from the width rich draws it in
    (counted here on the drawing) on."""
    from io import StringIO

    from rich.console import Console
    from rich.table import Table

    table = Table()
    for name in ("F_pT", "f_pT", "E"):
        table.add_column(name, justify="right", overflow="fold", no_wrap=False)
    table.add_row("123456.789", "-0.000125", "42")
    out = StringIO()
    Console(file=out, width=200, no_color=True, color_system=None, force_terminal=False).print(table)
    drawn = max(len(line.rstrip()) for line in out.getvalue().splitlines())
    for width in range(drawn - 6, drawn + 3):
        assert common._fits(table, None, width) == (width >= drawn), width


@pytest.mark.parametrize("no_color", [False, True])
def test_no_color_means_no_escape_codes_on_a_terminal(runner, monkeypatch, no_color):
    monkeypatch.setattr(common, "stdout_is_terminal", lambda: True)
    env = {"FORCE_COLOR": "1", "TERM": "xterm-256color", "COLUMNS": "100", "NO_COLOR": "1" if no_color else None}
    r = runner.invoke(app, TABLE_COMMANDS["sweep i,l"], env=env)
    assert r.exit_code == 0 and "gear TE" in r.stdout
    assert ("\x1b" in r.stdout) is (not no_color)  # styled on a terminal, unless NO_COLOR


def test_no_progress_bar_under_no_color(monkeypatch):
    monkeypatch.setattr(common, "stderr_is_terminal", lambda: True)
    monkeypatch.setenv("NO_COLOR", "1")
    assert common.Progress(10**6, 100.0, "x").bar is None
    monkeypatch.delenv("NO_COLOR")
    assert common.Progress(10**6, 100.0, "x").bar is not None
    monkeypatch.setenv("NO_COLOR", "")  # no-color.org: an empty value does not count
    assert common.Progress(10**6, 100.0, "x").bar is not None


# --- one meaning of -o, one announcement ------------------------------------------------------


def test_every_written_file_is_announced_the_same_way(runner, tmp_path):
    cases = [
        (["sweep", str(MCH50), "--i", "2:10:3", "-f", "csv", "-o", "{a}"], ["a"]),
        (["sweep", str(MCH50), "--param", "worm_pair.lead_error_mm=0:0.05:3", "-f", "json", "-o", "{a}"], ["a"]),
        (["simulate", str(MCH50), "--points", "10", "-o", "{a}"], ["a"]),
        (["synth", str(MCH50), "--targets", "4", "--runs", "1", "-o", "{a}", "--truth", "{b}"], ["a", "b"]),
        (["analyze", str(MCH50), "-o", "{a}"], ["a"]),
        (["check", str(CONFIGS / "eq6-belt-worm.toml"), "-o", "{a}"], ["a"]),  # passes (the MCH50 fails its limit)
    ]
    for n, (args, files) in enumerate(cases):
        paths = {k: tmp_path / f"{n}-{k}.out" for k in ("a", "b")}
        r = runner.invoke(app, [a.format(**{k: str(v) for k, v in paths.items()}) for a in args])
        assert r.exit_code == 0, (args, r.stderr)
        assert r.stdout == ""
        assert r.stderr == "".join(f"wrote {paths[k]}\n" for k in files), args
        assert all(paths[k].stat().st_size > 0 for k in files)


def test_new_announces_its_file_like_the_others(runner, tmp_path):
    path = tmp_path / "d.toml"
    r = runner.invoke(app, ["new", str(path)])
    assert r.exit_code == 0
    assert r.stderr == f"wrote {path}\nedit it, then run: wormgear check {path}\n"


def test_dash_means_stdout_for_sweep_csv(runner, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    a = runner.invoke(app, ["sweep", str(MCH50), "--i", "2:10:3", "-f", "csv", "-o", "-"])
    b = runner.invoke(app, ["sweep", str(MCH50), "--i", "2:10:3", "-f", "csv"])
    assert a.exit_code == 0 and a.stdout == b.stdout and a.stdout.startswith("i,l_mm,")
    assert not (tmp_path / "-").exists()


# --- one path to stdout -----------------------------------------------------------------------


@pytest.mark.parametrize("args", [
    ["sweep", str(MCH50), "--i", "2:10:9", "--l-mm", "100:300:11"],
    ["sweep", str(MCH50), "--i", "2:10:9", "--l-mm", "100:300:11", "-f", "csv"],
    ["sweep", str(MCH50), "--i", "2:10:9", "-f", "json"],
    ["sweep", str(MCH50), "--param", "worm_pair.lead_error_mm=0:0.05:250", "-f", "csv"],
    ["simulate", str(MCH50), "--points", "20"],
    ["synth", str(MCH50), "--targets", "4", "--runs", "1"],
])
def test_every_stdout_byte_goes_through_write_stdout(runner, monkeypatch, args):
    seen = []
    real = common.write_stdout

    def recording(data):
        seen.append(data.decode() if isinstance(data, bytes) else data)
        real(data)

    monkeypatch.setattr(common, "write_stdout", recording)
    r = runner.invoke(app, args)
    assert r.exit_code == 0 and r.stdout
    assert "".join(seen) == r.stdout

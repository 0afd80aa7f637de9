"""``wormgear upgrade``: the legacy two-table form rewritten as [[stage]] tables."""

from __future__ import annotations

import pytest

from tests.support.paths import CONFIGS, DATA, MCH50
from wormgear_cli.cli import app
from wormgear_cli.errors import SpecError
from wormgear_cli.spec.loader import load_spec, loads_spec
from wormgear_cli.spec.stages import record_values
from wormgear_cli.spec.upgrade import upgrade_text


def test_comments_travel_with_their_keys():
    text = MCH50.read_text()
    new = upgrade_text(text, str(MCH50)).text
    lines = new.splitlines()
    # the block before a key moves with it, to the key's new name and table
    k = lines.index("runout_mm = 0.012       # S1: radial runout of the worm's pitch cylinder")
    assert lines[k - 1].startswith("# stage reproduces the paper's 0.0424 deg") and "[stage.worm]" in lines[:k]
    # the head of the file stays on top; inline comments of headers go to the new headers
    assert lines[0] == "# MCH50 machining-centre rotary table: the paper's worked example (its Table 1)."
    assert "[stage.gear]  # gear 1" in lines and "[stage.pinion]  # gear 2" in lines
    # drive-level tables are copied with their comments
    assert "# mean: 0.070 deg = 252 arcsec." in lines
    assert not new.count("[gear_pair") and not new.count("[assembly]")


@pytest.mark.parametrize("name", ["mch50", "rotary-table-precision", "legacy/radar-pedestal-2start"])
def test_every_value_is_kept(name):
    path = (DATA if name.startswith("legacy") else CONFIGS) / f"{name}.toml"
    old, new = load_spec(path), loads_spec(upgrade_text(path.read_text(), str(path)).text, "new.toml")
    for a, b in zip(old.stages, new.stages):
        assert record_values(a) == record_values(b)
    assert (old.drive.name, old.materials, old.requirements) == (new.drive.name, new.materials, new.requirements)


def test_statistics_keys_become_stage_paths_and_dotted_files_fall_back():
    text = MCH50.read_text() + '\n[statistics]\n"assembly.wheel_eccentricity_mm" = { distribution = "uniform" }\n'
    new = upgrade_text(text, "x.toml").text
    assert '"stage.1.wheel.runout_mm" = { distribution = "uniform" }' in new
    from tests.support.specs import SPEC_HEAD

    dotted = SPEC_HEAD.replace("[gear_pair.output_gear]\nteeth = 144\n", "").replace(
        "pressure_angle_deg = 20\n", "pressure_angle_deg = 20\noutput_gear = { teeth = 144 }  # a comment\n", 1)
    assert loads_spec(dotted).stages[1].gear.teeth == 144
    up = upgrade_text(dotted, "d.toml")
    assert up.note.startswith("comments not kept") and "# a comment" not in up.text
    assert [record_values(s) for s in loads_spec(up.text).stages] == [record_values(s) for s in
                                                                      loads_spec(dotted).stages]


def test_a_stage_file_is_not_upgraded():
    new = upgrade_text(MCH50.read_text(), "m.toml").text
    with pytest.raises(SpecError, match=r"^n.toml: already a drive of \[\[stage\]\] tables; nothing to upgrade$"):
        upgrade_text(new, "n.toml")


def test_cli_writes_the_upgrade_and_never_the_input(runner, tmp_path):
    out = tmp_path / "new.toml"
    r = runner.invoke(app, ["upgrade", str(MCH50), "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    assert loads_spec(out.read_text()).form == "stages"
    r = runner.invoke(app, ["upgrade", str(MCH50)])
    assert r.exit_code == 0 and r.stdout == out.read_text()
    copy = tmp_path / "old.toml"
    copy.write_text(MCH50.read_text())
    r = runner.invoke(app, ["upgrade", str(copy), "-o", str(copy)])
    assert r.exit_code == 2 and copy.read_text() == MCH50.read_text()
    r = runner.invoke(app, ["upgrade", str(out)])
    assert r.exit_code == 2 and "nothing to upgrade" in r.stderr

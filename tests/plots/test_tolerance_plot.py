"""The tolerance plot's share-of-variance panel is readable: every key on its own row, no label
overlapping another, no legend over the data, and each share written where it is drawn."""

from __future__ import annotations

import pytest

pytest.importorskip("matplotlib")

from tests.support.paths import CONFIGS
from wormgear_cli.cli.tolerance import LABELS
from wormgear_cli.plots import pyplot
from wormgear_cli.plots.tolerance import figure
from wormgear_cli.spec.loader import load_spec
from wormgear_cli.tolerance import engine, study
from wormgear_cli.tolerance.report import short_key


@pytest.fixture(scope="module", params=["mch50.toml", "rotary-table-precision.toml"])
def drawn(request):
    spec = load_spec(CONFIGS / request.param)
    s = engine.setup(spec, engine.Options(samples=3000, seed=1, metrics="all"))
    summary = engine.run(s)
    doc = study.finish(s, summary, None, 3000)
    fig = figure(doc, summary.plot_values, engine.limits(s), LABELS)
    fig.canvas.draw()
    yield doc, fig
    pyplot().close(fig)


def _share_axis(fig):
    return next(ax for ax in fig.axes if ax.get_title().startswith("share of variance"))


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_every_key_has_its_own_row_and_no_legend(drawn):
    doc, fig = drawn
    ax = _share_axis(fig)
    assert ax.get_legend() is None
    keys = [k for k in doc["sensitivity"]["total_transmission_error"] if k != "remainder"]
    shown = [k for k in keys if any(s is not None and s[k] >= 0.005 for s in doc["sensitivity"].values())]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert len(labels) == len(shown) + 1 and len(set(labels)) == len(labels)
    assert labels[-1].startswith("remainder")


def test_no_tick_label_overlaps_another(drawn):
    _, fig = drawn
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        for ticks in (ax.get_yticklabels(), ax.get_xticklabels()):
            boxes = [t.get_window_extent(renderer) for t in ticks if t.get_text()]
            for a, b in zip(boxes, boxes[1:]):
                assert not _overlap(a, b), f"{ax.get_title()}: tick labels overlap"


def test_the_written_shares_are_the_documents(drawn):
    doc, fig = drawn
    ax = _share_axis(fig)
    written = {(round(t.get_position()[1]), round(t.get_position()[0])): float(t.get_text()) for t in ax.texts}
    metrics = [m for m, v in doc["sensitivity"].items() if v is not None]
    rows = [t.get_text() for t in ax.get_yticklabels()]
    for (r, c), value in written.items():
        key = rows[r]
        if key.startswith("remainder"):
            continue
        full = next(k for k in doc["sensitivity"][metrics[c]] if short_key(k) == key)
        assert value == pytest.approx(doc["sensitivity"][metrics[c]][full], abs=0.005)
    assert written, "no share written"


def test_the_share_panel_does_not_cover_a_histogram(drawn):
    _, fig = drawn
    renderer = fig.canvas.get_renderer()
    share = _share_axis(fig).get_tightbbox(renderer)
    for ax in fig.axes:
        if ax.get_title().startswith("share of variance"):
            continue
        assert not _overlap(share, ax.get_tightbbox(renderer))

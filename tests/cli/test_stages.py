"""cli.common.Stages: the stage spinner of long commands (diagnose), on a terminal only, after a delay."""

from __future__ import annotations

import time

from wormgear_cli.cli import common


def _terminal(monkeypatch, on: bool):
    monkeypatch.setattr(common, "stderr_is_terminal", lambda: on)
    monkeypatch.delenv("NO_COLOR", raising=False)


def test_shown_once_the_work_has_run_the_delay(monkeypatch):
    _terminal(monkeypatch, True)
    with common.Stages("first", after=0.05) as st:
        assert st.status is None  # not yet: a short run shows nothing
        deadline = time.monotonic() + 5.0
        while st.status is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert st.status is not None
        st.update("second")
        assert st.text == "second"
    assert st.status is None  # stopped on exit


def test_a_short_run_shows_nothing(monkeypatch):
    _terminal(monkeypatch, True)
    with common.Stages("first", after=30.0) as st:
        st.update("second")
    time.sleep(0.05)
    assert st.status is None and st.timer is None


def test_not_on_a_terminal_or_under_no_color(monkeypatch):
    _terminal(monkeypatch, False)
    assert common.Stages("x", after=0.0).timer is None
    _terminal(monkeypatch, True)
    monkeypatch.setenv("NO_COLOR", "1")
    assert common.Stages("x", after=0.0).timer is None

"""The compensate workflow's own choices (tests of the command are in tests/cli/test_compensate.py)."""

from __future__ import annotations


def test_the_default_table_span_is_the_turn_or_the_measured_arc_rounded_out():
    """Without --range: 0 to 360 for data around the whole turn; a partial arc (here -10.64 to
    0.43 deg, the field case's) rounded out to whole degrees, -11 to 1."""
    import numpy as np

    from wormgear_cli.workflows.compensate import _default_range

    assert _default_range(np.radians(np.arange(0.0, 360.0, 10.0))) == (0.0, 360.0)
    assert _default_range(np.radians(np.linspace(-10.64, 0.4274, 50))) == (-11.0, 1.0)

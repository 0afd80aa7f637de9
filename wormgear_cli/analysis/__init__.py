"""The analysis layer: what the model predicts for a drive.

:mod:`~wormgear_cli.analysis.accuracy` (each stage's transmission error and lost motion, the
totals), :mod:`~wormgear_cli.analysis.budget` (every error source as a line at the output),
:mod:`~wormgear_cli.analysis.requirements` (limits), :mod:`~wormgear_cli.analysis.simulate`
(the error curve), :mod:`~wormgear_cli.analysis.synth` (synthetic measurements),
:mod:`~wormgear_cli.analysis.sweep` and :mod:`~wormgear_cli.analysis.sweep_limits` (design
sweeps).

The names of the former module ``wormgear_cli.analysis`` are still found here, with a
DeprecationWarning naming their new home ``wormgear_cli.analysis.accuracy``.
"""

import importlib

from wormgear_cli.errors import moved

#: names of the former module ``wormgear_cli.analysis`` (now ``wormgear_cli.analysis.accuracy``)
_OLD_NAMES = frozenset({
    'Analysis', 'Deflections', 'INFO_COLUMNS', 'METRIC_COLUMNS', 'WormStage', 'analyze',
    'deflections', 'gear_eccentricity', 'gear_tangential_force', 'geometry', 'line_loads',
    'worm_stage', 'worm_tangential_force',
})


def __getattr__(name: str):
    if name in _OLD_NAMES:
        moved(f"wormgear_cli.analysis.{name}", f"wormgear_cli.analysis.accuracy.{name}")
        return getattr(importlib.import_module("wormgear_cli.analysis.accuracy"), name)
    raise AttributeError(f"module 'wormgear_cli.analysis' has no attribute {name!r}")

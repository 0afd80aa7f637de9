"""The stage models by kind: the one registry a new stage kind joins on the drive side.

Each model is a module ``wormgear_cli/drive/<kind>.py`` holding what the drive layer knows about
the kind: ``MEMBER_NAMES`` (what sits on the stage's input and output shaft, for labels),
``teeth(stage)`` (its ratio as whole numbers), ``mesh_orders(stage, after, of)`` (its meshes'
orders at the output), ``base_circle(stage)`` (the output member's base radius and teeth, for the
effect catalogue), ``tooth_deflection(spec, stage, stages)``, and the model proper: ``evaluate``, ``sources``,
``compliance`` (:mod:`wormgear_cli.drive.registry`) and ``sampled_totals`` (the stage's TE and
backlash of sampled drives, :mod:`wormgear_cli.tolerance.metrics`).  Its spec side is
:mod:`wormgear_cli.spec.kinds`.
"""

from types import ModuleType

from wormgear_cli.drive import belt, spur, worm

#: stage kind -> its model
MODELS: dict[str, ModuleType] = {"worm": worm, "spur": spur, "belt": belt}

"""Drive files written in the tests."""

SPEC_HEAD = """
[gear_pair]
module_mm = 2.5
pressure_angle_deg = 20
[gear_pair.output_gear]
teeth = 144
[gear_pair.pinion]
teeth = 18
[worm_pair]
module_mm = 2.5
normal_pressure_angle_deg = 20
lead_angle_deg = 3.178
[worm_pair.worm]
starts = 1
[worm_pair.wheel]
teeth = 30
"""


def deflections(spec, gear_force=None, worm_force=None, linear_at_spec_load=False):
    """(gear, worm) tooth deflections [mm] of a [worm, spur] drive at the given normal forces (default
    the stages' own), from each stage's one definition (:func:`wormgear_cli.drive.stiffness.deflection`)."""
    from types import SimpleNamespace

    from wormgear_cli.drive.stiffness import deflection

    worm, gear = spec.stages
    return SimpleNamespace(gear=deflection(spec, gear, gear_force, linear_at_spec_load),
                           worm=deflection(spec, worm, worm_force, linear_at_spec_load), model=spec.stiffness.model)


def line_loads(spec):
    """F_t K_A / b [N/mm] of the spur and the worm mesh of a [worm, spur] drive."""
    from wormgear_cli.drive.stiffness import line_load

    worm, gear = spec.stages
    return line_load(spec, gear), line_load(spec, worm)

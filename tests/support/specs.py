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

"""The physics of the parts: pure functions of numbers and arrays, no spec, no I/O.

Worm and spur stages (:mod:`~wormgear_cli.physics.worm`, :mod:`~wormgear_cli.physics.spur`),
tooth deflection (:mod:`~wormgear_cli.physics.deformation`, ISO 6336-1), thermal growth
(:mod:`~wormgear_cli.physics.thermal`), ISO 1328 tolerances
(:mod:`~wormgear_cli.physics.iso1328`) and the effect catalogue
(:mod:`~wormgear_cli.physics.effects`).  The spec layer reads these catalogues to validate a
drive file, so they sit below it.
"""

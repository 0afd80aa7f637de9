"""The drive model: the train of stages between the spec and the analyses.

A drive is an ordered list of stages from the motor to the output (worm, spur or belt).  This
layer holds the one model of the train and the one registry of its error sources that every
command reads:

* :mod:`~wormgear_cli.drive.train`: ratios, shaft turns per output turn, the orders at the output
  of every shaft and mesh, and the geometry the effect catalogue reads;
* :mod:`~wormgear_cli.drive.stiffness`: each gear mesh's tooth deflection under its load;
* :mod:`~wormgear_cli.drive.worm`, :mod:`~wormgear_cli.drive.spur`, :mod:`~wormgear_cli.drive.belt`:
  the per-kind stage models (TE and lost motion at the stage's own output shaft, its sources at
  the output, its compliance, its members, ratio and orders), and :mod:`~wormgear_cli.drive.models`,
  their registry (``MODELS``: kind -> model);
* :mod:`~wormgear_cli.drive.registry`: :func:`~wormgear_cli.drive.registry.build`, the registry.

Imports point one way: this layer reads spec records and physics, and the analyses read it.
"""

"""Correction tables a controller or a mount loads, and what they will leave.

One topic per module: :mod:`~wormgear_cli.compensation.model` (the error as a table needs it:
fitted orders per direction, per-target means where the orders do not explain the data),
:mod:`~wormgear_cli.compensation.table` (table points, how a controller applies a table, the
orders a table cannot carry), :mod:`~wormgear_cli.compensation.predict` (the ISO 230-2 figures a
repeat test will show, cross-validated over runs), :mod:`~wormgear_cli.compensation.pec` (a
mount's periodic error correction over one worm period), :mod:`~wormgear_cli.compensation.noise`
(scatter within and between runs) and :mod:`~wormgear_cli.compensation.scan` (the strongest
orders when none are given).  Pure numpy; the files are written by the output layer's writers
(:mod:`wormgear_cli.output.writers`).
"""

"""Per-command reports: the documents (JSON), CSV text and tables a command outputs.

Core code (no I/O, no typer, no rich), shared by the CLI and the Python API: each function
takes results of the core and returns data -- dicts for JSON, bytes/str for CSV, and
:class:`wormgear_cli.tables.Table` for tables.  Formatting of numbers lives in
:mod:`wormgear_cli.formats`.

* :mod:`wormgear_cli.reports.analyze` -- ``wormgear analyze`` (stages, totals, budget, values used).
* :mod:`wormgear_cli.reports.sweep` -- ``wormgear sweep`` ((i, l) grids and --param grids).
* :mod:`wormgear_cli.reports.simulate` -- ``wormgear simulate`` (dense scan and --at rows).
"""

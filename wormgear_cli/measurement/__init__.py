"""The measurement layer: measured (or planned) data and what can be read from it.

:mod:`~wormgear_cli.measurement.reader` (the record and the CSV reader),
:mod:`~wormgear_cli.measurement.iso230` (ISO 230-2 figures),
:mod:`~wormgear_cli.measurement.harmonics` (least squares at exact orders),
:mod:`~wormgear_cli.measurement.coverage` (the span covered, trends) and
:mod:`~wormgear_cli.measurement.orders` (which orders the data can resolve).

The names of the former module ``wormgear_cli.measurement`` are still found here, with a
DeprecationWarning naming their new home ``wormgear_cli.measurement.reader``.
"""

#: names of the former module ``wormgear_cli.measurement`` (now ``wormgear_cli.measurement.reader``)
_OLD_NAMES = frozenset({
    'ANGLE_UNITS', 'ARCSEC', 'BLOCK_CHARS', 'CANONICAL', 'DEFAULTS', 'ERROR_UNITS',
    'MAX_FILE_BYTES', 'Measurement', 'OPTIONAL', 'PLAUSIBLE_ERROR_P2P', 'RANGES', 'REQUIRED',
    'ReadOptions', 'SNIFF_LINES', 'detect_dialect', 'parse_measurement', 'plausibility',
    'read_bytes_bounded', 'read_measurement', 'suggest_map', 'time_restarts',
})


def __getattr__(name: str):
    if name in _OLD_NAMES:
        import importlib

        from wormgear_cli.errors import moved

        moved(f"wormgear_cli.measurement.{name}", f"wormgear_cli.measurement.reader.{name}")
        return getattr(importlib.import_module("wormgear_cli.measurement.reader"), name)
    raise AttributeError(f"module 'wormgear_cli.measurement' has no attribute {name!r}")

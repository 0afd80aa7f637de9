"""The measurement layer: measured (or planned) data and what can be read from it.

:mod:`~wormgear_cli.measurement.reader` (the record and what every input format shares),
:mod:`~wormgear_cli.measurement.readers` (the input formats as a registry: delimited tables,
TwinCAT Scope exports, ...),
:mod:`~wormgear_cli.measurement.resolution` (the resolution of the readings),
:mod:`~wormgear_cli.measurement.iso230` (ISO 230-2 figures),
:mod:`~wormgear_cli.measurement.harmonics` (least squares at exact orders),
:mod:`~wormgear_cli.measurement.coverage` (the span covered, trends) and
:mod:`~wormgear_cli.measurement.orders` (which orders the data can resolve).

The names of the former module ``wormgear_cli.measurement`` are still found here, with a
DeprecationWarning naming their new home ``wormgear_cli.measurement.reader``.
"""

import importlib

from wormgear_cli.errors import moved

#: names of the former module ``wormgear_cli.measurement`` (now ``wormgear_cli.measurement.reader``)
_OLD_NAMES = frozenset({
    'ANGLE_UNITS', 'ARCSEC', 'BLOCK_CHARS', 'CANONICAL', 'DEFAULTS', 'ERROR_UNITS',
    'MAX_FILE_BYTES', 'Measurement', 'OPTIONAL', 'PLAUSIBLE_ERROR_P2P', 'RANGES', 'REQUIRED',
    'ReadOptions', 'SNIFF_LINES', 'detect_dialect', 'parse_measurement', 'plausibility',
    'read_bytes_bounded', 'read_measurement', 'suggest_map', 'time_restarts',
})


#: old names whose home is now another module than ``reader``
_ELSEWHERE = {"read_measurement": "readers", "parse_measurement": "readers", "detect_dialect": "readers.text",
              "suggest_map": "readers.header", "plausibility": "readers.plausibility",
              "PLAUSIBLE_ERROR_P2P": "readers.plausibility", "RANGES": "readers.values"}


def __getattr__(name: str):
    if name in _OLD_NAMES:
        home = f"wormgear_cli.measurement.{_ELSEWHERE.get(name, 'reader')}"
        moved(f"wormgear_cli.measurement.{name}", f"{home}.{name}")
        return getattr(importlib.import_module(home), name)
    raise AttributeError(f"module 'wormgear_cli.measurement' has no attribute {name!r}")

"""wormgear-cli: accuracy of two-stage worm + spur gear drives.

The Python API (:mod:`wormgear_cli.api`, docs/api.md) is re-exported here
lazily: ``from wormgear_cli import analyze`` loads the API on first use, so
``import wormgear_cli`` (and every ``wormgear`` command) stays as fast as
before -- no numpy, no scipy at import.  ``sweep`` and ``tolerance`` are
not re-exported: those names are the core modules ``wormgear_cli.sweep`` and
``wormgear_cli.tolerance``; call them as ``wormgear_cli.api.sweep`` and
``wormgear_cli.api.tolerance``.
"""

__version__ = "0.1.0"

#: names of :mod:`wormgear_cli.api` available as ``wormgear_cli.NAME`` (never the name of a submodule)
_API = ("Angle", "AngleArray", "load_spec", "analyze", "simulate", "read_measurement", "measure", "diagnose")

__all__ = ["__version__", *_API]


def __getattr__(name):
    if name in _API:
        from wormgear_cli import api

        return getattr(api, name)
    raise AttributeError(f"module 'wormgear_cli' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_API])

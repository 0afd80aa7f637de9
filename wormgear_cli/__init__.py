"""wormgear-cli: accuracy of precision drives, worm, spur and belt stages in series.

The Python API (:mod:`wormgear_cli.api`, docs/api.md) is re-exported here
lazily: ``from wormgear_cli import analyze`` loads the API on first use, so
``import wormgear_cli`` (and every ``wormgear`` command) stays as fast as
before -- no numpy, no scipy at import.  ``sweep`` and ``tolerance`` are
not re-exported: those names are the core modules ``wormgear_cli.analysis.sweep`` and
``wormgear_cli.tolerance``; call them as ``wormgear_cli.api.sweep`` and
``wormgear_cli.api.tolerance``.
"""

import importlib
import importlib.util
import sys

__version__ = "0.1.0"

#: names of :mod:`wormgear_cli.api` available as ``wormgear_cli.NAME`` (never the name of a submodule)
_API = ("Angle", "AngleArray", "load_spec", "analyze", "simulate", "read_measurement", "measure", "diagnose",
        "compare", "compensate")

__all__ = ["__version__", *_API]


def __getattr__(name):
    if name in _API:
        from wormgear_cli import api  # lazy: the API and all it loads, on first use of one of its names

        return getattr(api, name)
    raise AttributeError(f"module 'wormgear_cli' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_API])


# --- old module paths ----------------------------------------------------------------------
# The modules moved into layer folders (docs/development.md, "Layout").  Code that imports an
# old path (``wormgear_cli.harmonics``, ``wormgear_cli.models.worm``, ...) gets the module at
# its new home and a DeprecationWarning naming it, as pvlib does when it moves a module.  The
# old paths will be removed in 0.3.

#: old module path -> its new home
MOVED_MODULES = {
    "wormgear_cli.io": "wormgear_cli.files",
    "wormgear_cli.tomlguard": "wormgear_cli.spec.toml",
    "wormgear_cli.template": "wormgear_cli.spec.template",
    "wormgear_cli.models": "wormgear_cli.physics",
    "wormgear_cli.models.iso1328": "wormgear_cli.physics.iso1328",
    "wormgear_cli.models.worm": "wormgear_cli.physics.worm",
    "wormgear_cli.models.gear": "wormgear_cli.physics.spur",
    "wormgear_cli.models.deformation": "wormgear_cli.physics.deformation",
    "wormgear_cli.models.thermal": "wormgear_cli.physics.thermal",
    "wormgear_cli.models.effects": "wormgear_cli.physics.effects",
    "wormgear_cli.models.geometry": "wormgear_cli.physics.geometry",
    "wormgear_cli.budget": "wormgear_cli.analysis.budget",
    "wormgear_cli.requirements": "wormgear_cli.analysis.requirements",
    "wormgear_cli.simulation": "wormgear_cli.analysis.simulate",
    "wormgear_cli.synth": "wormgear_cli.analysis.synth",
    "wormgear_cli.sweep": "wormgear_cli.analysis.sweep",
    "wormgear_cli.sweep_limits": "wormgear_cli.analysis.sweep_limits",
    "wormgear_cli.iso230": "wormgear_cli.measurement.iso230",
    "wormgear_cli.harmonics": "wormgear_cli.measurement.harmonics",
    "wormgear_cli.coverage": "wormgear_cli.measurement.coverage",
    "wormgear_cli.order_analysis": "wormgear_cli.measurement.orders",
    "wormgear_cli.measure_report": "wormgear_cli.workflows.measure",
    "wormgear_cli.formats": "wormgear_cli.output.formats",
    "wormgear_cli.tables": "wormgear_cli.output.tables",
    "wormgear_cli.reports": "wormgear_cli.output",
    "wormgear_cli.reports.analyze": "wormgear_cli.output.analyze",
    "wormgear_cli.reports.sweep": "wormgear_cli.output.sweep",
    "wormgear_cli.reports.simulate": "wormgear_cli.workflows.simulate",
}


class _MovedFinder:
    """Finds an old module path and hands out the module at its new home."""

    @staticmethod
    def find_spec(fullname, path=None, target=None):
        new = MOVED_MODULES.get(fullname)
        if new is None:
            return None

        # (a PEP 451 loader, create_module/exec_module; typeshed's LoaderProtocol asks for the legacy load_module)
        return importlib.util.spec_from_loader(fullname, _MovedLoader(fullname, new))  # type: ignore[arg-type]


class _MovedLoader:
    def __init__(self, old: str, new: str):
        self.old, self.new = old, new

    def create_module(self, spec):
        from wormgear_cli.errors import moved  # lazy: errors (and difflib) only when an old path is used

        moved(self.old, self.new, stacklevel=6)
        return importlib.import_module(self.new)

    def exec_module(self, module):  # the module at its new home is already executed
        pass


def _install_finder() -> None:
    if not any(isinstance(f, _MovedFinder) or f is _MovedFinder for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder)


_install_finder()


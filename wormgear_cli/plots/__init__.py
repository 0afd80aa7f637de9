"""Plots (optional extra ``plot``): matplotlib is imported only here, only when plotting.

Each command has its own module in this package; all draw with :func:`pyplot` and save
with :func:`save_figure`, the one plotting set-up: the non-interactive Agg backend, fixed
style settings, and byte-reproducible files (the same input gives the same bytes in PNG,
SVG and PDF: a fixed SVG id salt, no dates or software versions in the metadata).
"""

from __future__ import annotations

import io
from pathlib import Path

from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_write, check_output_path

PLOT_SUFFIXES = (".png", ".svg", ".pdf")
#: the one install hint of plotting: the package is installed from a checkout (pip install .), not
#: from the package index, so the hint names matplotlib itself (the 'plot' extra's one package)
INSTALL_HINT = "plotting needs matplotlib: pip install matplotlib"

#: resolution of PNG files [dots per inch]
DPI = 120

#: settings applied while a figure is saved: SVG element ids derive from this salt instead
#: of a random one; fonts are drawn as paths (no dependence on the viewer's fonts)
SAVE_RC = {"svg.hashsalt": "wormgear", "svg.fonttype": "path", "pdf.fonttype": 42}

#: metadata of each format: keys set to None are left out (dates, the matplotlib version)
METADATA = {
    "png": {"Software": None},
    "svg": {"Date": None, "Creator": None},
    "pdf": {"CreationDate": None, "ModDate": None, "Creator": None, "Producer": None},
}


def pyplot():
    """matplotlib.pyplot with the non-interactive Agg backend, or a UsageError with the install hint."""
    try:
        import matplotlib  # lazy: matplotlib (optional extra) is slow to import; only plots need it
    except ImportError:
        raise UsageError(INSTALL_HINT) from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt  # lazy: matplotlib (optional extra) is slow to import; only plots need it

    return plt


def check_plot_path(path: Path) -> None:
    """Refuse, before any work, a plot file name whose suffix matplotlib cannot write, or that names
    a directory or a file in a missing folder (:func:`wormgear_cli.files.check_output_path`)."""
    if Path(path).suffix.lower() not in PLOT_SUFFIXES:
        raise UsageError(f"{path}: --plot expects a file ending in {', '.join(PLOT_SUFFIXES)}")

    check_output_path(path, "--plot")


def figure_bytes(fig, fmt: str) -> bytes:
    """The file content of ``fig`` in ``fmt`` ("png", "svg", "pdf"): the same figure gives
    the same bytes on every run (:data:`SAVE_RC`, :data:`METADATA`)."""
    plt = pyplot()
    buf = io.BytesIO()
    with plt.rc_context(SAVE_RC):
        fig.savefig(buf, format=fmt, dpi=DPI, metadata=METADATA[fmt])
    return buf.getvalue()


def save_figure(fig, path: Path) -> None:
    """Save ``fig`` to ``path`` as one output of the run (atomic, committed with the
    others; see :func:`wormgear_cli.files.atomic_write`).

    Raises
    ------
    UsageError
        Unsupported suffix, or the file cannot be written.
    """
    check_plot_path(path)
    fmt = Path(path).suffix.lower().lstrip(".")
    atomic_write(path, figure_bytes(fig, fmt), option="--plot")

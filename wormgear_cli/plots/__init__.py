"""Plots (optional extra ``plot``): matplotlib is imported only here, only when plotting.

Each command has its own module in this package; all use :func:`pyplot`.
"""

from __future__ import annotations

from pathlib import Path

from wormgear_cli.errors import UsageError

PLOT_SUFFIXES = (".png", ".svg", ".pdf")
INSTALL_HINT = "plotting needs matplotlib: pip install 'wormgear-cli[plot]'"


def pyplot():
    """matplotlib.pyplot with the non-interactive Agg backend, or a UsageError with the install hint."""
    try:
        import matplotlib
    except ImportError:
        raise UsageError(INSTALL_HINT) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def check_plot_path(path: Path) -> None:
    """Refuse a plot file name whose suffix matplotlib cannot write."""
    if Path(path).suffix.lower() not in PLOT_SUFFIXES:
        raise UsageError(f"{path}: --plot expects a file ending in {', '.join(PLOT_SUFFIXES)}")


def save_figure(fig, path: Path) -> None:
    """Save atomically (temporary file + rename) with deterministic metadata."""
    import io

    from wormgear_cli.io import atomic_write

    check_plot_path(path)
    buf = io.BytesIO()
    fmt = Path(path).suffix.lower().lstrip(".")
    meta = {"Software": None} if fmt == "png" else ({"Date": None} if fmt == "svg" else {"CreationDate": None})
    fig.savefig(buf, format=fmt, dpi=120, metadata=meta)
    atomic_write(path, buf.getvalue())

"""The views of ``wormgear measure`` on a PHD2 guide log: the periodic-error tables and the frames as CSV."""

from __future__ import annotations

from wormgear_cli.output.formats import csv_block
from wormgear_cli.units import to_unit


def periodic_error_tables(doc: dict, view) -> list:
    """The periodic error of the document (``doc["periodic_error"]``) as tables: the figure, the worm
    harmonics and the orders fitted alongside, the sessions (more than one)."""
    # lazy: rich.markup only on this path; rich.text only on this path
    from rich.markup import escape
    from rich.text import Text

    pe = doc.get("periodic_error")
    if not pe or pe.get("worm_order") is None:
        return [Text(pe["note"])] if pe else []
    a, unit = view.a, view.unit
    ft = view.table(f"periodic error [{unit}]")
    ft.add_column("figure", overflow="fold")
    view.num(ft, "value")
    ft.add_row(escape("worm period [s]"), f"{pe['worm_period_s']:.5g}")
    ft.add_row(escape("worm order [cycles per RA turn]"), f"{pe['worm_order']:.6g}")
    ft.add_row("worm cycles covered", f"{pe['cycles']:.3g}")
    ft.add_row("PE peak to peak", a(pe["peak_to_peak"]))
    rms = pe["rms"]
    ft.add_row("RMS, each session about its mean", a(rms["raw"]))
    ft.add_row("RMS, drift removed", a(rms["drift_removed"]))
    ft.add_row("RMS, worm harmonics removed too", a(rms["worm_removed"]))
    ft.add_row("RMS, residual of the whole fit", a(rms["residual"]))
    # said under the table at the page's width (a caption would wrap at the narrow table's)
    said = Text(f"worm order from {pe['worm_from']}; PE: peak to peak of the worm harmonics over one worm "
                "period, each session's drift removed")
    ht = view.table(f"worm harmonics and orders fitted alongside [{unit}, phase deg]")
    for col in ("order", "period s", "amplitude", "+/-", "phase"):
        view.num(ht, col)
    ht.add_column("what", overflow="fold")
    for it in pe["harmonics"]:
        ht.add_row(*_cells(it, a), "worm" if it["harmonic"] == 1 else f"worm x {it['harmonic']}")
    for it in pe["fitted_alongside"]:
        ht.add_row(*_cells(it, a), escape(it["label"] or "a strong period found"))
    ht.caption = escape(f"amplitudes zero to peak; standard errors: {pe['standard_errors']}; the periodic error's own "
                        "fit (the worm's harmonics and these orders): the other tables fit other terms beside an "
                        "order, so its amplitude there may differ within the +/-")
    ht.caption_justify = "left"
    out = [ft, said, ht]
    if len(pe["sessions"]) > 1:
        st = view.table(f"sessions (runs) [{unit}; time min, angle deg]")
        for col in ("session", "frames", "start", "minutes", "RA axis", "drift p-p", "RMS"):
            view.num(st, col)
        for s in pe["sessions"]:
            st.add_row(str(s["session"]), str(s["frames"]), f"{s['start_s'] / 60:.1f}", f"{s['duration_s'] / 60:.1f}",
                       f"{s['start_angle_deg']:.2f}", a(s["drift_peak_to_peak"]), a(s["rms_drift_removed"]))
        st.caption = "RMS: the session's error with its drift removed"
        st.caption_justify = "left"
        out.append(st)
    return out


def _cells(it: dict, a) -> list:
    return [f"{it['order']:.6g}", f"{it['period_s']:.5g}", a(it["amplitude"]), a(it["amplitude_stderr"]),
            f"{it['phase_deg']:.1f}"]


#: the columns of the frames CSV (angle columns get the unit appended)
FRAME_COLUMNS = ("run", "time_s", "angle_deg", "error", "drift", "periodic_error")


def frames_csv(result, unit: str) -> str:
    """Every frame of a guide log as CSV: run (session), time_s, angle_deg (RA axis), the reconstructed
    error, its fitted drift and the worm's periodic error (empty without one), in ``unit``.  Readable
    again by ``measure`` as a table (angle_deg, error_UNIT, run, time_s)."""
    import numpy as np  # lazy: numpy only on this path


    m, pe = result.measurement, result.guide.periodic if result.guide is not None else None
    nan = np.full(len(m), np.nan)
    cols = [m.run.astype(float), m.time, np.degrees(m.angle), to_unit(m.error, unit),
            nan if pe is None else to_unit(pe.drift, unit), nan if pe is None else to_unit(pe.worm, unit)]
    header = [c if c in ("run", "time_s", "angle_deg") else f"{c}_{unit}" for c in FRAME_COLUMNS]
    return ",".join(header) + "\n" + csv_block([np.asarray(c, dtype=float) for c in cols]).decode("ascii")

"""Outputs of ``wormgear simulate``: the model's curve over a dense scan or at the rows of a
CSV, as CSV text or a JSON document, plus the curves for the plot.

Core code (no I/O beyond reading the ``--at`` measurement file through
:func:`wormgear_cli.measurement.reader.read_measurement`, no typer, no rich).  Angles are converted
to the output unit here.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.analysis.simulate import aligned_phases, periodic_sources
from wormgear_cli.analysis.simulate import simulate as run
from wormgear_cli.analysis.synth import resolve_effects
from wormgear_cli.output.formats import csv_text, fmt_number, json_text, one_row_per_line
from wormgear_cli.physics.effects import Signals, params_from_keys, params_to_keys
from wormgear_cli.physics.thermal import predicted_centre_distance_um_per_K, predicted_drift_arcsec_per_K
from wormgear_cli.units import to_unit

#: --phases values: as in the spec, or aligned so every source peaks at 0 deg
PHASE_CHOICES = ("spec", "aligned-error", "aligned-reversal")


@dataclass(frozen=True)
class SimulationReport:
    """What ``wormgear simulate`` outputs: ``text`` (CSV or JSON) and ``curves`` (a dict for
    :func:`wormgear_cli.plots.simulate.plot_simulation`; values in ``unit``)."""

    text: str
    curves: dict


def phase_map(spec, which: str) -> dict | None:
    """Source name -> phase [rad] for ``--phases`` ``which``; None keeps the spec's."""
    if which == "spec":
        return None
    return aligned_phases(spec, "error" if which == "aligned-error" else "reversal")


def effect_params(spec, requested: dict) -> dict | None:
    """The effects to simulate: the spec's merged with ``requested`` (name -> {key: value},
    :func:`wormgear_cli.analysis.synth.parse_effects`) as parameter records; None (the spec's own)
    when nothing is requested."""
    if not requested:
        return None

    return {n: params_from_keys(n, v) for n, v in resolve_effects(spec, requested).items()}


def _summary(v) -> dict:
    return {"min": float(np.min(v)), "max": float(np.max(v)), "peak_to_peak": float(np.ptp(v)),
            "rms": float(np.sqrt(np.mean(v * v)))}


def context(spec, unit: str, phases: dict | None, effects: dict | None) -> dict:
    """Spec-level facts shared by both JSON documents: sources (order, amplitude in ``unit``,
    phase), effects, the analyze totals and the predicted thermal centre-distance change."""
    from wormgear_cli.analysis.accuracy import analyze  # lazy: keeps analysis.accuracy off `simulate`'s start-up

    a = analyze(spec)
    sources = {}
    for src in periodic_sources(spec):
        ph = src.phase if phases is None else phases.get(src.name, src.phase)
        sources[src.name] = {"order": src.order, "amplitude": float(to_unit(src.amplitude, unit)),
                             "phase_deg": math.degrees(ph), "phase_key": src.phase_path}
    return {
        "sources": sources,
        "effects": {name: params_to_keys(name, p)
                    for name, p in (spec.effects if effects is None else effects).items()},
        "analyze": {"total_transmission_error": float(to_unit(a.angles["total_transmission_error"], unit)),
                    "total_backlash": float(to_unit(a.angles["total_backlash"], unit))},
        "predicted": {"centre_distance_um_per_K": predicted_centre_distance_um_per_K(spec),
                      **({"drift_arcsec_per_K": drift} if (drift := predicted_drift_arcsec_per_K(spec)) else {})},
    }


def dense(spec, points: int, revs: float, unit: str, fmt: str, temperature_c: float = 20.0,
          load_nm: float = 0.0, which: str = "spec", effects: dict | None = None) -> SimulationReport:
    """Forward and reverse curves at ``points`` output angles over ``revs`` turns (from 0,
    end excluded).  CSV columns: angle_deg, forward_<unit>, reverse_<unit>, common_<unit>
    (mean of both), lost_motion_<unit> (reverse - forward); ``fmt`` "json" gives the
    document with summaries and the curve."""
    phases = phase_map(spec, which)
    angle_deg = np.arange(points) * (360.0 * revs / points)
    theta = np.radians(angle_deg)
    fwd = run(spec, Signals.make(theta, 1.0, load_nm, temperature_c, 0.0), phases, effects=effects)
    rev = run(spec, Signals.make(theta, -1.0, load_nm, temperature_c, 0.0), phases, effects=effects)
    f_u, r_u = to_unit(fwd, unit), to_unit(rev, unit)
    common, lost = 0.5 * (f_u + r_u), r_u - f_u
    curves = {"kind": "dense", "drive": spec.drive.name, "unit": unit, "angle_deg": angle_deg,
              "forward": f_u, "reverse": r_u}
    if fmt == "json":
        doc = {
            "drive": spec.drive.name,
            "unit": unit,
            "points": int(points),
            "revolutions": float(revs),
            "conditions": {"temperature_C": float(temperature_c), "load_Nm": float(load_nm), "time_s": 0.0},
            "phases": which,
            **context(spec, unit, phases, effects),
            "summary": {
                "forward": _summary(f_u),
                "reverse": _summary(r_u),
                "common": _summary(common),
                "lost_motion": {"min": float(lost.min()), "max": float(lost.max()), "mean": float(lost.mean())},
            },
            "curve": {"angle_deg": angle_deg.tolist(), "forward": f_u.tolist(), "reverse": r_u.tolist()},
        }
        return SimulationReport(json_text(doc), curves)
    cols = ["angle_deg", f"forward_{unit}", f"reverse_{unit}", f"common_{unit}", f"lost_motion_{unit}"]
    rows = zip(angle_deg.tolist(), f_u.tolist(), r_u.tolist(), common.tolist(), lost.tolist())
    return SimulationReport(csv_text(cols, rows), curves)


#: rows of the --at CSV formatted per task (by the worker processes of ``--jobs``)
AT_ROWS_PER_TASK = 50_000


def _at_lines(state, span: tuple[int, int]) -> str:
    """CSV lines of rows [a, b) of the --at file with their simulated value (``j``: the index of
    the simulated column when the file has it already, else None: appended)."""
    import csv  # lazy: keeps csv off `simulate`'s start-up

    rows, sim, j = state
    a, b = span
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    values = [fmt_number(v) for v in sim[a:b].tolist()]
    if j is None:
        for row, v in zip(rows[a:b], values):
            w.writerow([*row, v])
    else:
        for row, v in zip(rows[a:b], values):
            w.writerow([*row[:j], v, *row[j + 1:]])
    return buf.getvalue()


def at_rows(spec, at, unit: str, fmt: str, temperature_c: float = 20.0, load_nm: float = 0.0,
            which: str = "spec", effects: dict | None = None, jobs: int = 1) -> SimulationReport:
    """The model at every row of the measurement CSV ``at`` (its load_Nm and temperature_C
    columns where present, else ``load_nm`` [N m] and ``temperature_c`` [degC]).

    CSV: the file's comments, preamble (as ``#`` comments), header and rows as they are (the rows
    the reader kept), plus (or replacing) the column simulated_error_<unit>; JSON: the simulated
    errors and, when the file has errors, the mean and RMS of measured - simulated.  ``jobs`` > 1:
    the CSV rows are formatted by that many worker processes (the same text).  Raises the
    reader's errors for a bad file."""
    import csv  # lazy: keeps csv off `simulate`'s start-up

    # lazy: keeps batch.pool, measurement.readers off `simulate`'s start-up
    from wormgear_cli.batch.pool import ordered_map
    from wormgear_cli.measurement.readers import read_measurement

    data = read_measurement(at, require_error=False)
    phases = phase_map(spec, which)
    load = data.load if "load_Nm" in data.present else np.full(len(data), float(load_nm))
    temp = data.temperature if "temperature_C" in data.present else np.full(len(data), float(temperature_c))
    signals = Signals(data.angle, data.direction, load, temp, data.time)
    sim = to_unit(run(spec, signals, phases, effects=effects), unit)
    column = f"simulated_error_{unit}"
    has_error = not np.all(np.isnan(data.error))
    curves = {"kind": "at", "drive": spec.drive.name, "unit": unit, "angle_deg": data.angle_deg,
              "direction": data.direction, "simulated": sim,
              "measured": to_unit(data.error, unit) if has_error else None, "source": str(at)}
    if fmt == "json":
        doc = {"drive": spec.drive.name, "data": str(at), "unit": unit, "rows": len(data), "phases": which,
               **context(spec, unit, phases, effects), "simulated_error": sim.tolist()}
        if has_error:
            resid = to_unit(data.error, unit) - sim
            doc["measured_minus_simulated"] = {"mean": float(resid.mean()),
                                               "rms": float(np.sqrt(np.mean(resid * resid)))}
        return SimulationReport(json_text(doc), curves)
    header = list(data.header)
    buf = io.StringIO()
    for line in data.comments:
        buf.write(line + "\n")
    for line in data.preamble:  # metadata without '#': written back as comments, so the file reads back plainly
        buf.write("# " + line + "\n")
    w = csv.writer(buf, lineterminator="\n")
    j = header.index(column) if column in header else None  # re-simulating a file that has the column: replaced
    w.writerow(header if j is not None else header + [column])
    spans = [(a, min(len(sim), a + AT_ROWS_PER_TASK)) for a in range(0, len(sim), AT_ROWS_PER_TASK)]
    for text in ordered_map(_at_lines, (data.rows, sim, j), spans, jobs):
        buf.write(text)
    return SimulationReport(one_row_per_line(buf.getvalue()), curves)

"""The one parser of synth's CSV in the tests."""

import csv
import io

import numpy as np


def csv_rows(text: str):
    lines = [ln for ln in text.splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    return rows[0], {c: np.array([float(r[j]) for r in rows[1:]]) for j, c in enumerate(rows[0])}

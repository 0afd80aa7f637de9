"""How the programs that load our files read and apply them, written from their sources' rules,
independently of the project's writers (tests only).

* LinuxCNC: ``usrmotLoadComp`` reads a joint compensation file line by line with
  ``sscanf("%lf %lf %lf")`` and stops at the first line that is not three numbers; type 0 holds
  (nominal, position reached forward, position reached reverse) and is turned into trims
  nominal - reached; type 1 holds the trims.  The motion controller keeps the entries between
  two sentinels (nominal -inf and +inf), refuses a nominal that does not increase, and in
  ``compute_screw_comp`` finds the entry below the commanded position and adds
  trim + slope * (position - nominal) of the direction of motion; the sentinels' slopes are 0,
  so the end values are held beyond the table.
* EQASCOM (EQMOD): ``Import`` skips line 1, reads ``!WormPeriod`` (rounded to whole seconds)
  and ``!StepsPerWorm``, skips ``#`` lines, splits each data line at single spaces (tabs turned
  into spaces) into time, motor position and PE, adds the PE of every WormPeriod-th row into one
  cycle, averages, then takes off idx * (curve[P-1] - curve[0]) / (P + 1).
"""

from __future__ import annotations

import math
import re

import numpy as np

_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")


def _sscanf3(line: str):
    """Three leading numbers of a line as C's sscanf("%lf %lf %lf") reads them, or None."""
    out, pos = [], 0
    for _ in range(3):
        m = _NUMBER.match(line, pos)
        if m is None:
            return None
        out.append(float(m.group(1)))
        pos = m.end()
    return out


class LinuxCncJoint:
    """A joint with a compensation file loaded as LinuxCNC loads it."""

    def __init__(self, text: str, file_type: int):
        self.nominal = [-math.inf]
        self.fwd = [0.0]
        self.rev = [0.0]
        self.errors = []
        for line in text.splitlines(keepends=True):
            triplet = _sscanf3(line)
            if triplet is None:
                break
            nom, f, r = triplet
            if file_type == 0:
                f, r = nom - f, nom - r
            if len(self.nominal) - 1 >= 256:
                self.errors.append("too many compensation entries")
                continue
            if nom <= self.nominal[-1]:
                self.errors.append("compensation values must increase")
                continue
            if len(self.nominal) == 1:  # the sentinel below takes the first entry's values, slope 0
                self.fwd[0], self.rev[0] = f, r
            self.nominal.append(nom)
            self.fwd.append(f)
            self.rev.append(r)
        self.nominal.append(math.inf)
        self.fwd.append(self.fwd[-1])
        self.rev.append(self.rev[-1])

    @property
    def entries(self) -> int:
        return len(self.nominal) - 2

    def correction(self, position: float, velocity: float) -> float:
        """compute_screw_comp: the value added to the command at ``position`` moving with ``velocity``."""
        i = 0
        while position < self.nominal[i]:
            i -= 1
        while position >= self.nominal[i + 1]:
            i += 1
        trims = self.fwd if velocity > 0 else self.rev
        if math.isinf(self.nominal[i]) or math.isinf(self.nominal[i + 1]):
            return trims[i]  # the sentinels: slope 0
        slope = (trims[i + 1] - trims[i]) / (self.nominal[i + 1] - self.nominal[i])
        return trims[i] + slope * (position - self.nominal[i])

    def apply(self, positions_deg, directions) -> np.ndarray:
        """Corrections [deg] at each commanded position moving in each direction (+1/-1)."""
        return np.array([self.correction(float(p), float(v)) for p, v in zip(positions_deg, directions)])


def eqascom_read(text: str) -> dict:
    """The PEC curve EQASCOM builds from a file: period, steps, signal per second, motor positions."""
    period = steps = None
    signal = cycles = positions = None
    idx = cycle_count = 0
    for lineno, line in enumerate(text.split("\n")):
        if lineno == 0:
            continue
        if line.startswith("!"):
            if "=" in line:
                key, value = line.split("=", 1)
                if key == "!WormPeriod":
                    period = int(math.floor(float(value) + 0.5))
                    signal, cycles, positions = np.zeros(period), np.zeros(period, int), np.zeros(period, int)
                    idx = 0
                elif key == "!StepsPerWorm":
                    steps = int(math.floor(float(value) + 0.5))
            continue
        if line.startswith("#"):
            continue
        line = line.replace("\t", " ")
        if " " not in line:
            continue
        first, rest = line.split(" ", 1)
        time_value = float(first)  # noqa: F841  (read, as EQASCOM does, and unused)
        if " " in rest:
            motor, pe = rest.split(" ", 1)
            if cycle_count == 0:
                positions[idx] = int(float(motor)) % steps if steps and int(float(motor)) > steps else int(float(motor))
            signal[idx] += float(pe)
            cycles[idx] = cycle_count + 1
        idx += 1
        if idx == period:
            cycle_count += 1
            idx = 0
    if not cycle_count:
        raise ValueError("Insufficient PEC samples")
    curve = signal / cycles
    drift = (curve[period - 1] - curve[0]) / (period + 1)
    curve = curve - np.arange(period) * drift
    return {"period": period, "steps": steps, "curve": curve, "positions": positions}

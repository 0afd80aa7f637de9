"""Design sweeps: the paper's gear-ratio / centre-distance study and any-parameter grids.

No I/O, no typer, no rich.  Two kinds of sweep:

* :class:`RatioDistanceSweep` -- the paper's Figure 1 study.  For every (i, l) of a grid a
  spur stage (``--stage N``, default the drive's last spur stage) gets R1 = l/(1+i),
  R2 = l i/(1+i); everything else comes from the drive spec.
  Evaluated in chunks, fully vectorised, with the exact maximum over phi from
  :func:`wormgear_cli.physics.spur.gear_te_max_fast` (the kinematic peak is found once per
  centre distance).  ``module`` snaps each point to whole tooth counts.
* :func:`param_rows` -- a grid over any numeric spec keys (TOML paths); each point is
  :func:`wormgear_cli.spec.loader.with_values` + :func:`wormgear_cli.analysis.accuracy.analyze`, so every row
  reproduces ``wormgear analyze`` exactly.

What is held fixed as i and l change (``hold``):

* ``"force"`` (default): the normal forces on the spur teeth and on the worm mesh stay at the
  spec's values (the paper's "holding other error sources constant").
* ``"torque"``: the output torque F_N cos(alpha) R2 stays at the spec's value, so the spur
  normal force scales as R2_spec / R2, and the loads of the stages before the swept one (the
  paper's worm mesh) follow the torque of its input shaft T_out / (O_k i), i.e. scale as
  i_spec / i.

Tooth deflection delta1 comes from the spec's stiffness model with the tooth counts implied
by the module, z1 = 2 R2 / m and z2 = 2 R1 / m (fractional between whole-tooth designs;
m = the spec's module, or the snapping module).  The gear backlash 2 Delta C1 / (m1 z1) uses
m1 z1 = 2 R2.  The other stages are unchanged by i and l except through their loads (torque
hold): the stages after the swept stage k reach the output as they are, the stage itself
divided by O_k (the product of the ratios after it), the stages before it divided by i O_k
(for the paper's [worm, spur] drive: the worm stage divided by i).

Units: lengths [mm], forces [N], angles [rad] (conversion to an output unit is the CLI's job).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np

from wormgear_cli.batch import shards
from wormgear_cli.batch.pool import ordered_map
from wormgear_cli.drive import belt, spur, worm
from wormgear_cli.drive.registry import build
from wormgear_cli.drive.stiffness import deflection
from wormgear_cli.errors import SpecError, UsageError, did_you_mean
from wormgear_cli.physics import spur as gear
from wormgear_cli.physics.deformation import spur_contact_ratio
from wormgear_cli.spec.kinds import KINDS
from wormgear_cli.spec.loader import DRIVE_FIELDS, FIELD_BY_PATH, with_values
from wormgear_cli.spec.stages import LEGACY_KEYS, STAGE_FIELD_BY_KEY, STAGE_KINDS, is_legacy_train

if TYPE_CHECKING:
    from wormgear_cli.drive.train import Train

#: the columns of the (i, l) sweep, in order; the first five are the stable interface
BASE_COLUMNS = ("i", "l_mm", "gear_transmission_error", "total_transmission_error", "total_backlash",
                "gear_backlash", "gear_te_phi_deg", "gear_deflection_um")
#: extra columns when snapping to whole teeth (``module``)
MODULE_COLUMNS = ("z1", "z2", "i_used", "l_used_mm")
#: extra columns with ``figures`` (snapped designs only): the sign-off figures of each design,
#: :data:`wormgear_cli.analysis.figures.FIGURE_COLUMNS` (kept equal to it by a test; named here so that
#: the sweep's columns are known without importing the budget and the acceptance test)
FIGURE_COLUMNS = ("budget_amplitude_linear", "budget_amplitude_statistical", "budget_amplitude_peak",
                  "budget_range_peak", "iso230_A", "iso230_E", "iso230_B", "iso230_M")
#: columns holding angles [rad] (converted to the output unit by the CLI)
ANGLE_COLUMNS = frozenset({"gear_transmission_error", "total_transmission_error", "total_backlash",
                           "gear_backlash", *FIGURE_COLUMNS})
#: columns holding whole numbers
INTEGER_COLUMNS = frozenset({"z1", "z2"})

HOLD_MODES = ("force", "torque")
#: most values of one --i, --l-mm axis (checked before any array is built; 80 MB per axis)
MAX_AXIS_VALUES = 10**7
#: most points of a --param grid (each is a full re-validated analyze, about 1.3 ms)
MAX_PARAM_POINTS = 100_000
#: the accepted snapping module [mm] (fine-pitch to very coarse spur gears)
MODULE_RANGE_MM = (0.05, 100.0)
#: most teeth of a snapped gear pair (z1 + z2) at the largest centre distance
MAX_TOOTH_SUM = 10**6
#: cap of :func:`undercut_min_teeth` (reached only for pressure angles below ~0.08 deg)
MAX_MIN_TEETH = 10**6
#: points evaluated per vectorised block (bounds memory; ~30 MB of temporaries)
CHUNK_POINTS = 1 << 16
#: grid points per block with ``figures`` (each kept design is a full analyze, budget and acceptance
#: prediction, ~50 ms: small blocks spread them over --jobs and move the progress bar)
FIGURE_CHUNK_POINTS = 64
#: the physical ranges of the (i, l) sweep's axes, by option: a gear ratio i = z1/z2 [-] and a centre
#: distance l [mm] (0.1 mm to 100 m).  Far beyond any spur stage built, they keep every value finite (at
#: l = 1e-300 mm the deflections overflowed to inf)
AXIS_RANGES = {"--i": (0.01, 1000.0), "--l-mm": (0.1, 100_000.0)}
#: the paper's thresholds for its findings: l "beyond 0.2 m", i "below about 6"
PAPER_L_KNEE_MM = 200.0
PAPER_I_KNEE = 6.0


# --- ranges and shards -----------------------------------------------------------------------


@dataclass(frozen=True)
class RangeSpec:
    """A checked ``START:STOP:N`` (``option`` names it in messages); no array built yet."""

    option: str
    text: str
    start: float
    stop: float
    n: int

    def values(self) -> np.ndarray:
        """The N values, START to STOP inclusive (numpy.linspace)."""
        return np.linspace(self.start, self.stop, self.n)


def parse_range_spec(text: str, option: str, positive: bool = False,
                     max_n: int = MAX_AXIS_VALUES, limit_note: str = "per axis") -> RangeSpec:
    """Check ``START:STOP:N`` without building the values (see :func:`parse_range`).

    N above ``max_n`` is refused here, before any array exists (a huge N would otherwise
    exhaust memory in numpy.linspace); ``limit_note`` says what the limit applies to.
    """
    where = f'{option} "{text}"'
    parts = text.split(":")
    if len(parts) != 3:
        raise UsageError(f"{where}: expected START:STOP:N (N values from START to STOP inclusive), "
                         "e.g. 2:10:9")
    nums = []
    for name, part in zip(("START", "STOP"), parts[:2]):
        try:
            v = float(part)
        except ValueError:
            raise UsageError(f'{where}: {name} "{part}" is not a number') from None
        if not math.isfinite(v):
            raise UsageError(f'{where}: {name} "{part}" is not a finite number')
        nums.append(v)
    start, stop = nums
    try:
        n_float = float(parts[2])
    except ValueError:
        raise UsageError(f'{where}: N "{parts[2]}" is not a whole number') from None
    if not math.isfinite(n_float) or not n_float.is_integer():
        raise UsageError(f'{where}: N "{parts[2]}" is not a whole number')
    n = int(n_float)
    if n < 1:
        raise UsageError(f"{where}: N must be at least 1, got {n}")
    if n > max_n:
        raise UsageError(f"{where}: N = {parts[2].strip()} is more than the limit of {max_n} values {limit_note}")
    if n == 1 and start != stop:
        raise UsageError(f"{where}: N = 1 needs START = STOP (got {start:g} and {stop:g})")
    if stop < start:
        raise UsageError(f"{where}: STOP ({stop:g}) is less than START ({start:g})")
    if positive and start <= 0.0:
        raise UsageError(f"{where}: values must be > 0 (START is {start:g})")
    check_axis(option, start, stop, where)
    return RangeSpec(option, text, start, stop, n)


def check_axis(option: str, low: float, high: float, where: str | None = None) -> None:
    """Refuse (UsageError naming ``where``, default ``option``) values from ``low`` to ``high`` of an
    (i, l) axis outside its physical range (:data:`AXIS_RANGES`; other options are not checked)."""
    if option not in AXIS_RANGES:
        return
    lo, hi = AXIS_RANGES[option]
    if not lo <= low <= high <= hi:
        bad = low if low < lo else high
        unit = " [mm]" if option == "--l-mm" else ""
        shown = f"{bad:g}" if not lo <= float(f"{bad:g}") <= hi else repr(float(bad))  # 1000.0001, not 1000
        raise UsageError(f"{where or option}: values must be from {lo:g} to {hi:g}{unit} (got {shown})")


def parse_range(text: str, option: str, positive: bool = False, whole: bool = False,
                max_n: int = MAX_AXIS_VALUES) -> np.ndarray:
    """``START:STOP:N`` -> N values from START to STOP inclusive (like numpy.linspace).

    Raises :class:`UsageError` naming ``option`` for: not three parts, a non-numeric or
    non-finite START/STOP, N not a whole number, N < 1, N > ``max_n`` (default
    :data:`MAX_AXIS_VALUES`), STOP < START with N > 1, N = 1 with START != STOP, values <= 0
    when ``positive``, non-whole values when ``whole``.
    """
    values = parse_range_spec(text, option, positive, max_n).values()
    if whole:
        _check_whole(values, f'{option} "{text}"')
    return values


def _check_whole(values: np.ndarray, where: str) -> None:
    bad = values[values != np.round(values)]
    if bad.size:
        raise UsageError(f"{where}: the key takes whole numbers, but the range gives {bad[0]:g}; "
                         "choose N so that (STOP - START)/(N - 1) is whole")


def parse_shard(text: str) -> tuple[int, int]:
    """``K/N`` (1 <= K <= N) -> (K, N); :class:`UsageError` naming ``--shard`` otherwise."""
    part = shards.parse(text)
    return part.k, part.n


def shard_bounds(total: int, k: int, n: int) -> tuple[int, int]:
    """Point indices [start, stop) of part ``k`` (1-based) of ``n`` contiguous parts of ``total``."""
    return shards.bounds(total, k, n)


# --- the (i, l) sweep ------------------------------------------------------------------------


def undercut_min_teeth(pressure_angle: float) -> int:
    """Smallest tooth count without undercut for a standard rack (addendum = 1 module):
    z_min = 2 / sin^2(alpha), rounded to the nearest whole number (17 for 20 deg, 32 for
    14.5 deg, 11 for 25 deg).  Profile-shifted pinions go lower (about 12 at 20 deg).

    Safe for any angle: the count grows without bound as alpha -> 0 and is capped at
    :data:`MAX_MIN_TEETH` (below about 0.08 deg, and for alpha <= 0 or NaN), so a degenerate
    angle skips every design instead of dividing by zero."""
    s2 = math.sin(pressure_angle) ** 2 if math.isfinite(pressure_angle) and pressure_angle > 0.0 else 0.0
    if not s2 * MAX_MIN_TEETH > 2.0:  # also catches s2 == 0 (underflow)
        return MAX_MIN_TEETH
    return max(1, min(MAX_MIN_TEETH, int(round(2.0 / s2))))


def check_module(module: float) -> None:
    """Refuse (UsageError naming ``module_mm``) a snapping module outside :data:`MODULE_RANGE_MM`."""
    lo, hi = MODULE_RANGE_MM
    if not (math.isfinite(module) and lo <= module <= hi):
        raise UsageError(f"module_mm {module:g}: expected a module from {lo:g} to {hi:g} [mm]", parameter="module_mm")


@dataclass(frozen=True)
class _Reference:
    """The spec's own design, which the sweep reproduces at its (i, l): the swept spur stage's ratio
    ``i``, centre distance ``l`` [mm], gear radius ``r2`` [mm] and normal force; ``after``: the product
    of the ratios after it (O_k, fixed); ``downstream_te``/``downstream_backlash``: the stages after it
    at the output, sum_{h>k} value_h / O_h [rad]; ``upstream_te``/``upstream_backlash``: the stages
    before it carried to its input shaft, sum_{h<k} value_h / (O_h / i_k) [rad] (reaching the output
    divided by i O_k: the ratio i of each design); ``upstream``: (stage, O_h / i_k) of those stages."""

    i: float
    l: float
    r2: float
    gear_force: float
    after: float
    downstream_te: float
    downstream_backlash: float
    upstream_te: float
    upstream_backlash: float
    upstream: tuple = ()

    @property
    def worm_force(self) -> float:
        """The load of the stages before the swept one (0: none has one; kept for the legacy name)."""
        return max((_load(st) for st, _ in self.upstream), default=0.0)


def _load(stage) -> float:
    return stage.effective_tension if stage.kind == "belt" else stage.normal_force


def spur_stage(spec, stage: int | None = None):
    """The spur stage ``--i``/``--l-mm`` act on: stage ``stage`` (1-based from the motor), default the
    drive's last spur stage.  UsageError naming ``--stage`` when the drive has no spur stage or stage N
    is not one."""
    kinds = ", ".join(f"{s.index} {s.kind}" for s in spec.stages)
    spurs = [s for s in spec.stages if s.kind == "spur"]
    if stage is None:
        if not spurs:
            raise UsageError(f"--i/--l-mm: the ratio and centre-distance sweep varies a spur stage; {spec.source} "
                             f"has none (stages: {kinds}); sweep another key with --param KEY=START:STOP:N, e.g. "
                             f"{spec.stages[-1].paths.get('module_mm', 'stage.1.module_mm')}=...")
        return spurs[-1]
    if not 1 <= stage <= len(spec.stages):
        raise UsageError(f"stage {stage}: {spec.source} has {len(spec.stages)} stage"
                         f"{'s' if len(spec.stages) != 1 else ''} (stages: {kinds})", parameter="stage")
    if spec.stages[stage - 1].kind != "spur":
        hint = (f"; its spur stage{'s are' if len(spurs) > 1 else ' is'} "
                + ", ".join(str(s.index) for s in spurs)) if spurs else "; it has no spur stage"
        raise UsageError(f"stage {stage}: stage {stage} of {spec.source} is a {spec.stages[stage - 1].kind} stage, "
                         f"the ratio and centre-distance sweep varies a spur stage{hint}", parameter="stage")
    return spec.stages[stage - 1]


def _reference(spec, st) -> _Reference:
    reg = build(spec)
    t, k = cast("Train", reg.train), st.index  # (the registry's record holds its train untyped)
    i_k = t.ratios[k - 1]
    down = [r for r in reg.results if r.index > k]
    up = [r for r in reg.results if r.index < k]
    # added from the output back, as the registry's totals (for the paper's [worm, spur] drive: nothing
    # after the spur stage, the worm stage / 1 before it, so the total is the paper's te + w_te / i)
    down_te = down_bl = 0.0
    for r in reversed(down):
        down_te, down_bl = down_te + r.transmission_error / r.after, down_bl + r.backlash / r.after
    up_te = up_bl = 0.0
    for r in reversed(up):
        up_te, up_bl = up_te + r.transmission_error / (r.after / i_k), up_bl + r.backlash / (r.after / i_k)
    g = st.gear.teeth
    return _Reference(i=g / st.pinion.teeth, l=st.module * (g + st.pinion.teeth) / 2.0, r2=st.module * g / 2.0,
                      gear_force=st.normal_force, after=t.after(st), downstream_te=down_te,
                      downstream_backlash=down_bl, upstream_te=up_te, upstream_backlash=up_bl,
                      upstream=tuple((t.stages[r.index - 1], r.after / i_k) for r in up))


class RatioDistanceSweep:
    """The (i, l) response surface of a spur stage of a drive (see the module docstring).

    ``i_values`` and ``l_values`` [mm] span the grid; points are numbered row-major with i
    outermost: point p is (i_values[p // len(l_values)], l_values[p % len(l_values)]).
    ``module`` [mm]: snap each point to whole teeth (:meth:`snap`), skipping designs whose
    smaller gear has fewer than ``min_teeth`` teeth (default :func:`undercut_min_teeth`).
    ``stage``: the spur stage swept (1-based; default the last spur stage, :func:`spur_stage`).
    ``figures``: with ``module``, add each whole-tooth design's sign-off figures (:data:`FIGURE_COLUMNS`:
    the budget's totals and the ISO 230-2 figures on the spec's test plan), from
    :meth:`design_spec` through :func:`wormgear_cli.analysis.figures.figures`, i.e. what ``wormgear
    analyze --format csv`` prints for that design.
    """

    def __init__(self, spec, i_values, l_values, hold: str = "force", module: float | None = None,
                 min_teeth: int | None = None, stage: int | None = None, figures: bool = False):
        st = spur_stage(spec, stage)
        if hold not in HOLD_MODES:
            raise UsageError(f'--hold "{hold}": expected one of {", ".join(HOLD_MODES)}')
        if module is not None:
            check_module(module)
        if figures and module is None:
            raise UsageError("figures: the budget and ISO 230-2 figures are those of whole-tooth designs, which "
                             "the sweep makes at a module: give module_mm (or sweep the tooth counts with --param "
                             "stage.N.gear.teeth=...)", parameter="figures")
        if min_teeth is not None and min_teeth < 1:
            raise UsageError(f"min_pinion_teeth {min_teeth}: expected a whole number >= 1",
                             parameter="min_pinion_teeth")
        self.spec = spec
        self.stage = st
        self.i_values = np.asarray(i_values, dtype=float)
        self.l_values = np.asarray(l_values, dtype=float)
        if module is not None and self.l_values.size:
            zsum = 2.0 * float(self.l_values.max()) / module
            if zsum > MAX_TOOTH_SUM:
                raise UsageError(f"module_mm {module:g}: l = {float(self.l_values.max()):g} mm needs {zsum:.3g} "
                                 f"teeth (z1 + z2 = 2 l / m); at most {MAX_TOOTH_SUM} are supported, use a larger "
                                 "module or a shorter --l-mm range", parameter="module_mm")
        self.hold = hold
        self.module = module
        self.figures = bool(figures)
        #: (i, l, z1, z2, why) of the first design --figures left out as an invalid drive (None: none
        #: seen in this process)
        self.first_invalid: tuple | None = None
        self.alpha = st.pressure_angle
        self.eccentricity = st.model_eccentricity  # the one the chosen kinematics uses, as analyze
        self.min_teeth = (min_teeth if min_teeth is not None else undercut_min_teeth(self.alpha)) \
            if module is not None else None
        self._face_width_given = st.origins.get("face_width_mm") == "spec"
        self._contact_ratio_given = "contact_ratio" in spec.raw.get("stiffness", {})
        self.reference = _reference(spec, st)
        # the structure: the kinematic peak depends on l only -> once per grid centre distance
        # (precomputed for up to one block of l values; a longer l axis gets it per block,
        # which keeps memory bounded: every l then appears at most twice in a block)
        self._paper = st.kinematics == "paper"  # the involute stage has no kinematic peak to search
        self._peak = gear.kinematic_peak(self.l_values, self.eccentricity, self.alpha) \
            if self._paper and module is None and self.l_values.size <= CHUNK_POINTS else None
        self._peak_blocks: dict = {}

    # -- shape -----------------------------------------------------------------------------------

    @property
    def size(self) -> int:
        """Number of grid points (before any skipping)."""
        return self.i_values.size * self.l_values.size

    @property
    def columns(self) -> tuple:
        return BASE_COLUMNS + (MODULE_COLUMNS if self.module is not None else ()) + \
            (FIGURE_COLUMNS if self.figures else ())

    @property
    def chunk_points(self) -> int:
        """Grid points per block of work (:meth:`spans`)."""
        return FIGURE_CHUNK_POINTS if self.figures else CHUNK_POINTS

    def grid_index(self, start: int, stop: int):
        """(i index, l index) of points [start, stop)."""
        p = np.arange(start, stop, dtype=np.int64)
        return p // self.l_values.size, p % self.l_values.size

    def run_bounds(self, shard: tuple[int, int] | None = None) -> tuple[int, int]:
        """Point indices [start, stop) of a run (all points, or part K of N for ``shard``).

        Raises UsageError for a snapped grid (``module``) of which no design is left."""
        start, stop = shard_bounds(self.size, *shard) if shard else (0, self.size)
        if self.module is not None and shard is None and self.kept_count() == 0:
            raise UsageError(f"no design left: at --module-mm {self.module:g} every point of the grid has a gear "
                             f"with fewer than {self.min_teeth} teeth; raise l, or lower --min-pinion-teeth")
        return start, stop

    # -- snapping ----------------------------------------------------------------------------------

    def snap(self, i, l):
        """Whole tooth counts for nominal (i, l) at the sweep's module M.

        Rule: the tooth sum z1 + z2 = round(2 l / M) keeps the centre distance as close as the
        module allows; the pinion gets z2 = round((z1 + z2) / (1 + i)), the output gear the rest.
        Returns (z1, z2, keep) with keep = min(z1, z2) >= min_teeth.  Rounding is half-to-even.
        """
        m = self.module
        if m is None:
            raise ValueError("snap: the sweep has no module to snap to")
        zsum = np.rint(2.0 * np.asarray(l, dtype=float) / m)
        z2 = np.rint(zsum / (1.0 + np.asarray(i, dtype=float)))
        z1 = zsum - z2
        keep = np.minimum(z1, z2) >= self.min_teeth
        return z1, z2, keep

    def kept_count(self, start: int = 0, stop: int | None = None) -> int:
        """Points of [start, stop) that survive snapping (all of them without a module)."""
        stop = self.size if stop is None else stop
        if self.module is None:
            return max(0, stop - start)
        total = 0
        for a in range(start, stop, CHUNK_POINTS):
            ii, li = self.grid_index(a, min(stop, a + CHUNK_POINTS))
            total += int(np.count_nonzero(self.snap(self.i_values[ii], self.l_values[li])[2]))
        return total

    # -- evaluation --------------------------------------------------------------------------------

    def _deflections(self, z1, z2, module, r2, ratio):
        """delta1 [mm] of the swept spur mesh and the load factor of the stages before it, per design."""
        spec, ref, st = self.spec, self.reference, self.stage
        if self.hold == "torque":
            gear_force = ref.gear_force * ref.r2 / r2
            up_scale = ref.i / ratio
        else:
            gear_force = np.full(np.shape(r2), ref.gear_force)
            up_scale = np.ones(np.shape(r2))
        face = st.face_width if (self._face_width_given or module == st.module) else 10.0 * module
        shadow_stage = st._replace(module=module, face_width=face, gear=st.gear._replace(teeth=z1),
                                   pinion=st.pinion._replace(teeth=z2))
        stiff = spec.stiffness if self._contact_ratio_given else spec.stiffness._replace(
            contact_ratio=spur_contact_ratio(z1, z2, st.pressure_angle))
        shadow = dataclasses.replace(spec, stiffness=stiff)
        d1 = deflection(shadow, shadow_stage, gear_force)
        return np.broadcast_to(np.asarray(d1, dtype=float), np.shape(r2)), up_scale

    def _upstream(self, scale):
        """(TE, backlash) [rad] of the stages before the swept one at its input shaft, each stage's load
        times ``scale`` (the torque hold: their torques follow 1 / i), by their kinds' models."""
        te = bl = 0.0
        for stage, per in reversed(self.reference.upstream):
            if stage.kind == "belt":
                t, b = belt.totals(stage._replace(effective_tension=stage.effective_tension * scale))
            else:
                d = deflection(self.spec, stage, stage.normal_force * scale)
                t, b = (worm if stage.kind == "worm" else spur).totals(stage, d)
            te, bl = te + t / per, bl + b / per
        return te, bl

    def evaluate(self, i, l, peak=None, teeth=None) -> dict:
        """Metrics [rad, mm, um, deg] of designs with ratio ``i`` and centre distance ``l`` [mm]
        (arrays), with the sweep's module, hold and spec.  ``peak``: the kinematic peak per
        design (:func:`~wormgear_cli.physics.spur.kinematic_peak`), computed when omitted.
        ``teeth``: whole (z1, z2) of snapped designs (then R = m z / 2 exactly); otherwise
        z = 2 R / m.  Totals at the output: the stages after the swept one as they are, the swept
        stage / O_k, the stages before it / (i O_k)."""
        i = np.asarray(i, dtype=float)
        l = np.asarray(l, dtype=float)
        i, l = np.broadcast_arrays(i, l)
        st = self.stage
        m = self.module if self.module is not None else st.module
        if teeth is None:
            r1 = l / (1.0 + i)
            r2 = l * i / (1.0 + i)
            z1, z2 = 2.0 * r2 / m, 2.0 * r1 / m
        else:
            z1, z2 = (np.asarray(z, dtype=float) for z in teeth)
            r1, r2 = m * z2 / 2.0, m * z1 / 2.0
        d1, up_scale = self._deflections(z1, z2, m, r2, i)
        if not self._paper:  # involute: the same stage as analyze's (physics.spur.involute_stage)
            inv = gear.involute_stage(r2, self.alpha, self.eccentricity, st.centre_distance_error, d1,
                                      st.gear.thickness_deviation + st.pinion.thickness_deviation)
            te, bl, bl_def = inv.te_eccentricity + inv.te_deformation, inv.backlash, inv.backlash_deformation
            phi = np.full(np.shape(te), 0.5 * np.pi)  # e sin(phi) peaks at a quarter turn of the pinion
        else:
            if peak is None:
                peak = gear.kinematic_peak(r1 + r2, self.eccentricity, self.alpha)
            te, phi = gear.gear_te_max_fast(r1, r2, self.eccentricity, self.alpha, d1, peak=peak)
            bl = gear.gear_backlash_max(m, z1, self.eccentricity, self.alpha, d1)
            bl_def = gear.pitch_arc_to_angle(2.0 * d1, m, z1)  # 2 delta1 on the gear's pitch arc
        if st.anti_backlash != "none":  # a split pinion: the deflection's part and the stated residual
            bl = 0.0 + bl_def + float(st.residual_lost_motion)
        ref = self.reference
        w_te: np.ndarray | float
        w_bl: np.ndarray | float
        if self.hold == "torque" and ref.worm_force > 0.0:
            # the loads before the swept stage follow its input torque T_out / (O_k i): those stages at
            # their scaled loads, by the same models as analyze (the deflection is not linear in the force:
            # ISO 6336-1's low-load stiffness), once per distinct ratio
            scales, where = np.unique(np.asarray(up_scale, dtype=float), return_inverse=True)
            u_te, u_bl = self._upstream(scales)
            w_te = np.broadcast_to(u_te, scales.shape)[where].reshape(np.shape(up_scale))
            w_bl = np.broadcast_to(u_bl, scales.shape)[where].reshape(np.shape(up_scale))
        else:
            w_te, w_bl = ref.upstream_te, ref.upstream_backlash
        return {
            "gear_transmission_error": te,
            "total_transmission_error": ref.downstream_te + te / ref.after + w_te / i,
            "total_backlash": ref.downstream_backlash + bl / ref.after + w_bl / i,
            "gear_backlash": bl,
            "gear_te_phi_deg": np.degrees(phi),
            "gear_deflection_um": d1 * 1e3,
        }

    def _peak_at(self, li) -> tuple:
        """The kinematic peak at l indices ``li``.  A long l axis is done in fixed blocks of
        :data:`CHUNK_POINTS` l values (the last two kept), so a value never depends on which
        points share its block of work: shards stay byte-identical to the whole run."""
        if self._peak is not None:
            return tuple(p[li] for p in self._peak)
        size = CHUNK_POINTS
        block = li // size
        out = [np.empty(li.size) for _ in range(5)]
        for b in np.unique(block).tolist():
            pk = self._peak_blocks.get(b)
            if pk is None:
                pk = gear.kinematic_peak(self.l_values[b * size:(b + 1) * size], self.eccentricity, self.alpha)
                if len(self._peak_blocks) >= 2:
                    self._peak_blocks.pop(next(iter(self._peak_blocks)))
                self._peak_blocks[b] = pk
            sel = block == b
            for o, p in zip(out, pk):
                o[sel] = p[li[sel] - b * size]
        return tuple(out)

    def chunk(self, a: int, b: int) -> dict:
        """Column arrays for grid points [a, b) (see :meth:`chunks`)."""
        ii, li = self.grid_index(a, b)
        i_nom, l_nom = self.i_values[ii], self.l_values[li]
        point = np.arange(a, b, dtype=np.int64)
        if self.module is None:
            peak = self._peak_at(li) if self._paper else None
            metrics = self.evaluate(i_nom, l_nom, peak=peak)
            return {"i": i_nom, "l_mm": l_nom, **metrics, "_point": point}
        z1, z2, keep = self.snap(i_nom, l_nom)
        z1, z2, i_nom, l_nom, point = z1[keep], z2[keep], i_nom[keep], l_nom[keep], point[keep]
        i_used, l_used = z1 / z2, self.module * (z1 + z2) / 2.0
        peak = None
        if self._paper:
            uniq, inverse = np.unique(l_used, return_inverse=True)
            peak = tuple(p[inverse] for p in gear.kinematic_peak(uniq, self.eccentricity, self.alpha))
        metrics = self.evaluate(i_used, l_used, peak=peak, teeth=(z1, z2))
        out = {"i": i_nom, "l_mm": l_nom, **metrics, "z1": z1.astype(np.int64), "z2": z2.astype(np.int64),
               "i_used": i_used, "l_used_mm": l_used, "_point": point}
        if self.figures:
            figures, valid, first = self._figures(z1, z2)
            out = {k: v[valid] for k, v in out.items()}  # a design the spec does not hold for is left out
            out.update(figures)
            if first is not None and self.first_invalid is None:
                k = int(np.flatnonzero(~valid)[0])
                self.first_invalid = (float(i_nom[k]), float(l_nom[k]), int(z1[k]), int(z2[k]), first)
        return out

    def design_spec(self, z1: int, z2: int):
        """The drive spec of one whole-tooth design: the swept stage with gear and pinion teeth ``z1``,
        ``z2`` at the sweep's module, its load and the loads of the stages before it as the sweep holds
        them (``force``: the spec's; ``torque``: the swept stage's force times R2_spec / R2, the stages
        before it times i_spec / i), written out so that the loader does not derive them again.
        ``wormgear analyze`` of this spec gives the row's totals (a test holds them equal)."""
        if self.module is None:
            raise ValueError("design_spec: the sweep has no module (its designs are not whole-tooth)")
        ref, k = self.reference, self.stage.index
        z1, z2 = int(z1), int(z2)
        ratio, r2 = z1 / z2, self.module * z1 / 2.0
        torque = self.hold == "torque"
        changes: dict[str, float | int] = {f"stage.{k}.gear.teeth": z1, f"stage.{k}.pinion.teeth": z2,
                                            f"stage.{k}.module_mm": float(self.module),
                                            f"stage.{k}.normal_force_N": ref.gear_force * (ref.r2 / r2 if torque
                                                                                            else 1.0)}
        for up, _ in self.reference.upstream:
            changes[f"stage.{up.index}.{KINDS[up.kind].load_key}"] = _load(up) * (ref.i / ratio if torque else 1.0)
        return with_values(self.spec, changes)

    def _figures(self, z1, z2) -> tuple[dict, np.ndarray, str | None]:
        """:data:`FIGURE_COLUMNS` arrays [rad] of the snapped designs (z1, z2), one full analysis each,
        of the designs the drive spec holds for (``valid``; e.g. a wheel beyond ISO 1328's scope of
        teeth for its accuracy grade is not), and the first other's SpecError message (None: none)."""
        from wormgear_cli.analysis.figures import figures  # lazy: keeps the budget and acceptance test off `sweep`

        cols: dict[str, list[float]] = {c: [] for c in FIGURE_COLUMNS}
        valid = np.ones(np.size(z1), dtype=bool)
        first = None
        for k, (a, b) in enumerate(zip(np.asarray(z1).tolist(), np.asarray(z2).tolist())):
            try:
                design = self.design_spec(a, b)
            except SpecError as exc:
                valid[k] = False
                first = first or exc.problems[0]
                continue
            f = figures(design)
            for c in FIGURE_COLUMNS:
                cols[c].append(f[c])
        return {c: np.asarray(v, dtype=float) for c, v in cols.items()}, valid, first

    def spans(self, start: int = 0, stop: int | None = None, chunk: int | None = None) -> list[tuple[int, int]]:
        """The chunks [a, b) of grid points [start, stop), as :meth:`chunks` computes them (``chunk``:
        default :attr:`chunk_points`)."""
        stop = self.size if stop is None else stop
        chunk = self.chunk_points if chunk is None else chunk
        return [(a, min(stop, a + chunk)) for a in range(start, stop, chunk)]

    def chunks(self, start: int = 0, stop: int | None = None, chunk: int | None = None,
               progress: Callable[[int], None] | None = None, jobs: int = 1) -> Iterator[dict]:
        """Column arrays for grid points [start, stop), in blocks of ``chunk`` points.

        Each block is a dict column -> array (see :attr:`columns`) plus ``"_point"``, the grid
        index of each row.  With a module, skipped designs are left out.  ``progress(n)`` is
        called after each block with the number of grid points it covered.  ``jobs`` > 1:
        the blocks are computed by that many worker processes (same blocks, same values).
        """
        spans = self.spans(start, stop, chunk)
        for block, (a, b) in zip(ordered_map(_chunk, self, spans, jobs), spans):
            if progress is not None:
                progress(b - a)
            yield block

    def collect(self, start: int = 0, stop: int | None = None,
                progress: Callable[[int], None] | None = None, jobs: int = 1) -> dict:
        """All of :meth:`chunks` concatenated into one dict of arrays."""
        blocks = list(self.chunks(start, stop, progress=progress, jobs=jobs))
        keys = self.columns + ("_point",)
        if not blocks:
            return {k: np.empty(0) for k in keys}
        return {k: np.concatenate([blk[k] for blk in blocks]) for k in keys}

    # -- summary -----------------------------------------------------------------------------------

    def continuous(self) -> RatioDistanceSweep:
        """The same sweep without snapping (the paper's continuous study)."""
        if self.module is None:
            return self
        return RatioDistanceSweep(self.spec, self.i_values, self.l_values, self.hold, stage=self.stage.index)

    def gear_te(self, i, l) -> np.ndarray:
        """Gear-stage TE [rad] of the continuous model at arbitrary (i, l)."""
        return self.continuous().evaluate(i, l)["gear_transmission_error"]


def _chunk(sweep: RatioDistanceSweep, span: tuple[int, int]) -> dict:
    """One chunk of a sweep (a worker's task: :func:`~wormgear_cli.batch.pool.ordered_map`)."""
    return sweep.chunk(*span)


def check_train(spec, stage: int | None = None) -> None:
    """UsageError unless ``spec`` has a spur stage for the (i, l) sweep (:func:`spur_stage`)."""
    spur_stage(spec, stage)


def ratio_distance_sweep(spec, i_range: RangeSpec | None, l_range: RangeSpec | None,
                         hold: str | None = None, module: float | None = None,
                         min_teeth: int | None = None, stage: int | None = None,
                         figures: bool = False) -> RatioDistanceSweep:
    """The (i, l) sweep of ``spec``'s spur stage ``stage`` (default the last spur stage) over checked
    ranges; an axis not given is the stage's own value (i = z1/z2, l = m (z1 + z2)/2 [mm]).  ``hold``
    None means "force"."""
    st = spur_stage(spec, stage)
    i_values = i_range.values() if i_range is not None else np.array([st.gear.teeth / st.pinion.teeth])
    l_values = l_range.values() if l_range is not None else \
        np.array([st.module * (st.gear.teeth + st.pinion.teeth) / 2.0])
    return RatioDistanceSweep(spec, i_values, l_values, hold=hold or "force", module=module, min_teeth=min_teeth,
                              stage=st.index, figures=figures)


def best_points(data: dict) -> dict:
    """Index of the lowest total TE and of the lowest gear TE among collected points
    (first in point order on ties); empty when there are no points."""
    if data["gear_transmission_error"].size == 0:
        return {}
    return {"total_transmission_error": int(np.argmin(data["total_transmission_error"])),
            "gear_transmission_error": int(np.argmin(data["gear_transmission_error"]))}


def _fall_pct(before: float, after: float) -> float:
    """Percent fall from ``before`` to ``after``; NaN when ``before`` is not > 0 (undefined)."""
    return 100.0 * (1.0 - after / before) if before > 0.0 else float("nan")


def _usable(*values) -> bool:
    """True when every gear TE value is finite and > 0, so ratios and logarithms are defined."""
    return all(bool(np.all(np.isfinite(v) & (np.asarray(v) > 0.0))) for v in values)


def _zero_te_reason(sweep: RatioDistanceSweep) -> str:
    """The statement of a finding that cannot be evaluated because gear TE is 0 (or undefined)."""
    if sweep.eccentricity == 0.0 and sweep.reference.gear_force == 0.0:
        cause = "gear TE is 0 everywhere (the spec has no gear eccentricity and no gear tooth load)"
    else:
        cause = "gear TE is 0 or undefined at points this check needs"
    return f"not testable on this grid: {cause}, so its relative changes are undefined"


def findings(sweep: RatioDistanceSweep, max_axis: int = 21) -> list[dict]:
    """The paper's three findings on the gear-stage TE, checked on the sweep's grid ranges.

    Evaluated exactly with the continuous model (also when snapping) at the spec's own i and
    l clipped into the grid (``i_ref``, ``l_ref``):

    1. ``l_more_sensitive_than_i``: the elasticities e_l = d ln TE / d ln l and
       e_i = d ln TE / d ln i (central differences, step 1e-4) over up to ``max_axis`` x
       ``max_axis`` grid points; holds when median |e_l| > median |e_i|.  Also the relative
       change of TE across the grid's l range (at i_ref) and i range (at l_ref).
    2. ``l_gain_fades_beyond_200mm``: with w = min(200 - l_min, l_max - 200), TE falls X % from
       l = 200 - w to 200 mm and Y % from 200 to 200 + w (at i_ref); holds when Y < X.
       Not testable (holds = None) unless l_min < 200 < l_max.
    3. ``i_matters_below_6``: the same around i = 6 (at l_ref); holds when the fall above 6 is
       smaller than below it.  Not testable unless i_min < 6 < i_max.

    A finding is also not testable (holds = None, the statement says why) when the gear TE it
    needs is 0 -- a drive without gear eccentricity and without gear tooth load -- since its
    relative changes are then undefined.

    Returns a list of dicts with ``id``, ``holds`` (True/False/None), ``statement`` and numbers.
    """
    iv, lv = sweep.i_values, sweep.l_values
    i_min, i_max, l_min, l_max = float(iv[0]), float(iv[-1]), float(lv[0]), float(lv[-1])
    ref = sweep.reference
    i_ref = float(np.clip(ref.i, i_min, i_max))
    l_ref = float(np.clip(ref.l, l_min, l_max))
    te = sweep.gear_te
    out: list[dict[str, object]] = []

    # 1: elasticities on a subsample of the grid
    si = np.unique(np.linspace(0, iv.size - 1, min(iv.size, max_axis)).round().astype(int))
    sl = np.unique(np.linspace(0, lv.size - 1, min(lv.size, max_axis)).round().astype(int))
    ig, lg = np.meshgrid(iv[si], lv[sl], indexing="ij")
    ig, lg = ig.ravel(), lg.ravel()
    h = 1e-4
    dlog = math.log1p(h) - math.log1p(-h)
    stencil = (te(ig, lg * (1 + h)), te(ig, lg * (1 - h)), te(ig * (1 + h), lg), te(ig * (1 - h), lg))
    ends = (te(i_ref, l_max), te(i_ref, l_min), te(i_max, l_ref), te(i_min, l_ref))
    if not _usable(*stencil, *ends):
        out.append({"id": "l_more_sensitive_than_i", "holds": None, "statement": _zero_te_reason(sweep)})
    else:
        out.append(_sensitivity(stencil, ends, dlog, iv, lv, i_ref, l_ref))

    # 2 and 3: diminishing returns around the paper's knees
    for key, knee, lo, hi, unit, other, other_value, fn in (
        ("l_gain_fades_beyond_200mm", PAPER_L_KNEE_MM, l_min, l_max, " mm", "i", i_ref,
         lambda x: te(i_ref, x)),
        ("i_matters_below_6", PAPER_I_KNEE, i_min, i_max, "", "l", l_ref, lambda x: te(x, l_ref)),
    ):
        other_txt = f"{other} = {other_value:g}" + (" mm" if other == "l" else "")
        name = "l" if key.startswith("l_") else "i"
        if not lo < knee < hi:
            out.append({"id": key, "holds": None,
                        "statement": f"not testable on this grid: the {name} range {lo:g}..{hi:g}{unit} does "
                                     f"not straddle {knee:g}{unit}"})
            continue
        w = min(knee - lo, hi - knee)
        a, b, c = (float(fn(x)) for x in (knee - w, knee, knee + w))
        if not _usable(a, b, c):
            out.append({"id": key, "holds": None, "statement": _zero_te_reason(sweep)})
            continue
        before, after = _fall_pct(a, b), _fall_pct(b, c)
        ratio = (b - c) / (a - b) if a != b else float("nan")
        holds = after < before
        if key.startswith("l_"):
            head = f"the gain from l {'fades' if holds else 'does not fade'} beyond {knee:g} mm"
        else:
            head = f"i {'matters mainly' if holds else 'does not matter mainly'} below {knee:g}"
        out.append({
            "id": key, "holds": bool(holds),
            "statement": (f"{head}: gear TE falls {before:.1f} % from {name} = {knee - w:g} to {knee:g}{unit} and "
                          f"{after:.1f} % from {knee:g} to {knee + w:g}{unit} (at {other_txt}); the absolute "
                          f"fall above is {ratio:.2f} x the fall below"),
            "window": [knee - w, knee, knee + w], "fall_below_pct": before, "fall_above_pct": after,
            "absolute_fall_ratio": ratio, ("i_ref" if name == "l" else "l_ref_mm"): other_value,
        })
    return out


def _sensitivity(stencil, ends, dlog, iv, lv, i_ref, l_ref) -> dict:
    """Finding 1 from the gear TE on the difference stencil and at the grid's ends (all > 0)."""
    l_up, l_down, i_up, i_down = stencil
    e_l = (np.log(l_up) - np.log(l_down)) / dlog
    e_i = (np.log(i_up) - np.log(i_down)) / dlog
    med_l, med_i = float(np.median(e_l)), float(np.median(e_i))
    share = float(100.0 * np.mean(np.abs(e_l) > np.abs(e_i)))
    te_l_max, te_l_min, te_i_max, te_i_min = ends
    span_l = float(100.0 * (te_l_max / te_l_min - 1.0))
    span_i = float(100.0 * (te_i_max / te_i_min - 1.0))
    i_min, i_max, l_min, l_max = float(iv[0]), float(iv[-1]), float(lv[0]), float(lv[-1])
    holds = abs(med_l) > abs(med_i)
    spans = []
    if lv.size > 1:
        spans.append(f"l from {l_min:g} to {l_max:g} mm changes it by {span_l:+.1f} % (at i = {i_ref:g})")
    if iv.size > 1:
        spans.append(f"i from {i_min:g} to {i_max:g} {'by' if spans else 'changes it by'} {span_i:+.1f} % "
                     f"(at l = {l_ref:g} mm)")
    return {
        "id": "l_more_sensitive_than_i",
        "holds": bool(holds),
        "statement": (f"gear TE is {'more' if holds else 'less'} sensitive to l than to i: +1 % in l changes "
                      f"it by {med_l:+.2f} %, +1 % in i by {med_i:+.2f} % (medians over the grid; l dominates "
                      f"at {share:.0f} % of points)" + ("; " + ", ".join(spans) if spans else "")),
        "elasticity_l": med_l, "elasticity_i": med_i, "l_dominates_pct": share,
        "change_over_l_range_pct": span_l, "change_over_i_range_pct": span_i,
        "i_ref": i_ref, "l_ref_mm": l_ref,
    }


# --- any-parameter sweeps --------------------------------------------------------------------


@dataclass(frozen=True)
class ParamAxis:
    """One ``--param KEY=START:STOP:N``: the spec key and its values (in the key's unit)."""

    key: str
    values: tuple


def _effect_param_keys() -> list[str]:
    from wormgear_cli.physics.effects import EFFECTS  # lazy: keeps physics.effects off `sweep`'s start-up

    return [f"effects.{name}.{p.key}" for name, eff in EFFECTS.items() for p in eff.params]


def parse_param(text: str, spec=None) -> ParamAxis:
    """``KEY=START:STOP:N`` over a numeric spec key; :class:`UsageError` naming it otherwise.

    KEY is a TOML path: a drive-level key (``stiffness.iso_ka``), a stage key ``stage.N.KEY`` (N the
    stage's position from the motor) or, for a drive of one worm and one spur stage, a key of the
    legacy two-table form (``worm_pair.lead_error_mm``).  With ``spec`` the key is checked against that
    drive (the stage's kind); without, against the keys any drive may have.  N is checked against
    :data:`MAX_PARAM_POINTS` before the values are built.  Keys of the ``[effects.*]`` tables are
    refused with their own message: effects feed ``simulate`` and ``diagnose``, not the ``analyze``
    metrics a --param sweep reports, so every row would be the same.
    """
    if "=" not in text:
        raise UsageError(f'--param "{text}": expected KEY=START:STOP:N, e.g. worm_pair.lead_error_mm=0:0.05:11')
    key, rng = text.split("=", 1)
    key = key.strip()
    field = _param_field(key, spec)
    if field.kind not in ("float", "int"):
        what = {"str": f"takes {field.expected()}", "floats": "is an array"}.get(field.kind, "is not a number")
        raise UsageError(f"--param {key}: not a numeric key (it {what}); only single numbers can be swept")
    where = f"--param {key}"
    values = parse_range_spec(rng, where, max_n=MAX_PARAM_POINTS, limit_note="in a --param sweep").values()
    if field.kind == "int":
        _check_whole(values, f'{where} "{rng}"')
    for v in values:
        if (field.lo is not None and (v < field.lo or (field.lo_open and v == field.lo))) or \
                (field.hi is not None and (v > field.hi or (field.hi_open and v == field.hi))):
            raise UsageError(f"--param {key}: value {v:g} is out of range, expected {field.expected()}")
    vals = tuple(int(round(v)) for v in values) if field.kind == "int" else tuple(float(v) for v in values)
    return ParamAxis(key, vals)


def _param_field(key: str, spec):
    """The schema's :class:`~wormgear_cli.spec.fields.Field` of a --param key (see :func:`parse_param`)."""
    parts = key.split(".", 2)
    if len(parts) == 3 and parts[0] == "stage" and parts[1].isdigit():
        return _stage_field(key, int(parts[1]), parts[2], spec)
    drive_level = {f.path: f for f in DRIVE_FIELDS}
    legacy_ok = spec is None or is_legacy_train(spec.stages)
    field = drive_level.get(key) or (FIELD_BY_PATH.get(key) if legacy_ok else None)
    if field is not None:
        return field
    effect_keys = _effect_param_keys()
    if key in effect_keys:
        raise UsageError(f"--param {key}: effect parameters cannot be swept with --param (the [effects.*] "
                         "tables feed simulate and diagnose, not the analyze metrics of a sweep); vary it "
                         "in the drive file and run wormgear simulate")
    if key in LEGACY_KEYS and not legacy_ok:
        kind, stage_key = LEGACY_KEYS[key]
        where = [s.paths[stage_key] for s in spec.stages if s.kind == kind and stage_key in STAGE_FIELD_BY_KEY[kind]]
        raise UsageError(f"--param {key}: a key of the legacy two-table form; this drive names its stages' keys "
                         f"stage.N.KEY" + (f" (did you mean {' or '.join(where)}?)" if where else
                                           f" and has no {kind} stage"))
    known = list(drive_level) + (list(FIELD_BY_PATH) if legacy_ok else []) + effect_keys
    if spec is not None:
        known += [p for s in spec.stages for p in s.paths.values()]
    hint = did_you_mean(key, known, otherwise=" (see the key reference: wormgear new)")
    raise UsageError(f"--param {key}: unknown spec key{hint}")


def _stage_field(key: str, n: int, stage_key: str, spec):
    """The Field of ``stage.N.KEY``: of stage N's kind with ``spec``, else of any kind having KEY."""
    if spec is None:
        for kind in STAGE_KINDS:
            if stage_key in STAGE_FIELD_BY_KEY[kind]:
                return STAGE_FIELD_BY_KEY[kind][stage_key]
        every = sorted({k for fs in STAGE_FIELD_BY_KEY.values() for k in fs})
        hint = did_you_mean(stage_key, every, show=lambda m: f"stage.{n}.{m}")
        raise UsageError(f"--param {key}: unknown stage key{hint}")
    count = len(spec.stages)
    if not 1 <= n <= count:
        raise UsageError(f"--param {key}: {spec.source} has {count} stage{'s' if count != 1 else ''}, no stage {n}")
    kind = spec.stages[n - 1].kind
    field = STAGE_FIELD_BY_KEY[kind].get(stage_key)
    if field is None:
        others = [k for k in STAGE_KINDS if k != kind and stage_key in STAGE_FIELD_BY_KEY[k]]
        hint = (f" (a key of {' and '.join(others)} stages; stage {n} is a {kind} stage)" if others else
                did_you_mean(stage_key, list(STAGE_FIELD_BY_KEY[kind]), show=lambda m: f"stage.{n}.{m}"))
        raise UsageError(f"--param {key}: unknown key of stage {n} ({kind}){hint}")
    return field


def check_param_axes(axes: list[ParamAxis]) -> None:
    """Each key once, and at most :data:`MAX_PARAM_POINTS` points in the whole grid."""
    seen = set()
    for ax in axes:
        if ax.key in seen:
            raise UsageError(f"--param {ax.key}: given twice; give each key once")
        seen.add(ax.key)
    total = param_size(axes)
    if total > MAX_PARAM_POINTS:
        counts = " x ".join(str(len(ax.values)) for ax in axes)
        raise UsageError(f"--param: {counts} = {total} points are more than the limit of {MAX_PARAM_POINTS} "
                         "points of a --param sweep (each point is a full analyze, about 1.3 ms); use fewer "
                         "values")


def param_size(axes: list[ParamAxis]) -> int:
    return math.prod(len(ax.values) for ax in axes)


def param_rows(spec, axes: list[ParamAxis], start: int = 0, stop: int | None = None,
               progress: Callable[[int], None] | None = None) -> Iterator[tuple]:
    """(values, Analysis) for points [start, stop) of the grid over ``axes`` (row-major, the
    first axis outermost).  Each point is ``analyze(with_values(spec, {key: value, ...}))``."""
    from wormgear_cli.analysis.accuracy import analyze  # lazy: keeps analysis.accuracy off `sweep`'s start-up

    total = param_size(axes)
    stop = total if stop is None else stop
    grid = itertools.islice(itertools.product(*(ax.values for ax in axes)), start, stop)
    for values in grid:
        result = analyze(with_values(spec, dict(zip((ax.key for ax in axes), values))))
        if progress is not None:
            progress(1)
        yield values, result

"""The train: stages in series from the motor to the output, their ratios, shaft speeds and orders.

Shafts are numbered 0 (the motor shaft, the first stage's input) to n (the output shaft); stage k
(1-based) turns shaft k-1 into shaft k with the ratio i_k (input turns per output turn of the
stage: z_wheel/z_worm, z_gear/z_pinion, z_driven/z_driver).  Shaft s turns

    O_s = prod_{k > s} i_k

times per output turn (O_n = 1).  A stage's angular error at its own output shaft k reaches the
output divided by O_k, the product of the ratios after it; its lost motion likewise:
Delta theta = sum_h b_h / O_h (for the paper's two stages: Delta phi_cc + Delta phi_wc / i_c).

Orders at the output (cycles per output revolution): a shaft's once-per-turn errors at O_s; a
mesh's tooth-frequency errors at z O_slow (z the teeth of the member on the slower shaft: a worm
with s starts turns z/s times per wheel turn, its mesh at z per wheel turn); a belt's
once-per-belt-revolution errors at z_driven O_driven / z_belt, not a whole number in general.
Source: the reference facts' "Drive trains of several stages" (the aggregation is the paper's
Delta phi = sum_h Delta phi_h / i_h).
"""

import math
from typing import Any, NamedTuple

from wormgear_cli.drive.models import MODELS
from wormgear_cli.spec.kinds import KINDS


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Train(NamedTuple):
    """The stages (spec records, motor -> output), their ratios i_k and the shaft turns O_s.

    ``turns[s]``: turns of shaft s per output turn, s = 0 (motor) .. n (output, 1.0)."""

    stages: tuple
    ratios: tuple
    turns: tuple

    @property
    def total_ratio(self) -> float:
        """Motor turns per output turn, prod_k i_k."""
        return self.turns[0]

    def after(self, stage) -> float:
        """The product of the ratios after ``stage`` (its output shaft's turns per output turn)."""
        return self.turns[stage.index]

    def before(self, stage) -> float:
        """Turns of ``stage``'s input shaft per output turn."""
        return self.turns[stage.index - 1]

    @property
    def kinds(self) -> tuple:
        return tuple(s.kind for s in self.stages)


def train(stages) -> Train:
    """The :class:`Train` of stage records ``stages`` (motor -> output)."""
    ratios = tuple(float(s.ratio) for s in stages)
    turns = [1.0]
    for s in reversed(stages):
        out_teeth, in_teeth = _teeth(s)
        turns.append(turns[-1] * out_teeth / in_teeth)  # O_{k-1} = O_k z_out / z_in
    return Train(tuple(stages), ratios, tuple(reversed(turns)))


def _teeth(stage) -> tuple[int, int]:
    """(teeth of the output member, teeth or starts of the input member) of a stage (its model's)."""
    return MODELS[stage.kind].teeth(stage)


def of(spec) -> Train:
    """The train of a loaded spec."""
    return train(spec.stages)


# --- orders ---------------------------------------------------------------------------------------------------

#: what sits on a stage's input and output shaft, by kind (its model's ``MEMBER_NAMES``)
MEMBER_NAMES = {kind: model.MEMBER_NAMES for kind, model in MODELS.items()}


class Order(NamedTuple):
    """An order at the output of a shaft or a mesh: ``order`` [cycles per output revolution],
    ``kind`` ("shaft", "mesh" or "belt": once per belt revolution), ``stage`` (1-based; 0 for the
    motor shaft), ``label``."""

    order: float
    kind: str
    stage: int
    label: str


#: words a stage's name cannot stand for it in a label (``gear of gear``): the members' and the default names
_PLAIN_NAMES = frozenset({n for names in MEMBER_NAMES.values() for n in names}
                         | {k.default_name for k in KINDS.values()})


def _of(t: Train, st) -> str:
    """`` of NAME`` when the train has more than one stage of ``st``'s kind (names then tell them apart;
    `` of stage N`` for a name that is a member's word, such as ``gear``)."""
    if sum(1 for s in t.stages if s.kind == st.kind) <= 1:
        return ""
    plain = st.name.rstrip("0123456789") in _PLAIN_NAMES  # gear, or a numbered default name such as gear3
    return f" of stage {st.index}" if plain else f" of {st.name}"


def shaft_label(t: Train, s: int) -> str:
    """A shaft's name from what sits on it: ``output shaft (wheel)``, ``motor shaft (driving pulley)``,
    ``shaft 1 (driven pulley, worm)``."""
    on = []
    if s >= 1:
        on.append(MEMBER_NAMES[t.stages[s - 1].kind][1] + _of(t, t.stages[s - 1]))
    if s < len(t.stages):
        on.append(MEMBER_NAMES[t.stages[s].kind][0] + _of(t, t.stages[s]))
    where = "motor shaft" if s == 0 else "output shaft" if s == len(t.stages) else f"shaft {s}"
    return f"{where} ({', '.join(on)})"


def orders(t: Train) -> list[Order]:
    """Every shaft's and every mesh's order at the output, shafts first (output -> motor), then each
    stage's meshes (output -> motor)."""
    out = [Order(t.turns[s], "shaft", s, shaft_label(t, s)) for s in range(len(t.stages), -1, -1)]
    for st in t.stages[::-1]:
        after, of = t.after(st), _of(t, st)
        out += [Order(o, kind, st.index, label) for o, kind, label in MODELS[st.kind].mesh_orders(st, after, of)]
    return out


# --- the geometry the effect catalogue reads ------------------------------------------------------------------


def drive_geometry(spec, t: Train | None = None):
    """The :class:`~wormgear_cli.physics.geometry.DriveGeometry` of any train, for the effect
    catalogue and the diagnosis: the output member is the last stage's (spur gear, worm wheel or
    driven pulley), the worm the last worm stage's, the intermediate shaft the last stage's input
    shaft (none when that is the worm shaft).  ``gear_ratio`` is that shaft's turns per output turn
    (the last stage's ratio).  For the legacy [worm, spur] train these are the values the catalogue
    was written for (i_c for both the intermediate shaft and the reduction after the worm)."""
    from wormgear_cli.physics.geometry import DriveGeometry  # lazy: keeps physics.geometry off `analyze`'s start-up

    t = t or of(spec)
    last = t.stages[-1]
    r_out = last.output_radius
    r_base, teeth = MODELS[last.kind].base_circle(last)
    worms = [s for s in t.stages if s.kind == "worm"]
    legacy = t.kinds == ("worm", "spur")
    labels = () if legacy else tuple((o.order, o.label) for o in orders(t))
    # the intermediate shaft: the output stage's input shaft, unless it is a worm shaft (worm_runout's)
    inter = t.turns[-2] if last.kind != "worm" else 0.0
    extra: dict[str, Any] = {} if legacy else {"kinds": t.kinds, "intermediate": inter}
    if worms:
        w = worms[-1]
        worm_diameter = w.worm.starts * w.module / math.tan(w.lead_angle)
        if not legacy:
            extra["worm_after"] = t.after(w)
        return DriveGeometry(r_out, r_base, w.output_radius, t.after(w) if legacy else t.turns[-2], t.before(w),
                             teeth, w.transverse_pressure_angle, (worm_diameter + 2.0 * w.output_radius) / 2.0,
                             w.worm.starts, labels, **extra)
    return DriveGeometry(r_out, r_base, r_out, t.turns[-2], t.turns[0], teeth, 0.0, 0.0, 1, labels,
                         worm_after=0.0, **extra)

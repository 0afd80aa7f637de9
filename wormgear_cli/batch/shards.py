"""Parts of a run: ``--shard K/N`` and ``--shard auto`` (the part from a scheduler's job array).

Part K of N covers the items [floor((K-1) S / N), floor(K S / N)) of a run of S items
(samples, grid points): contiguous, in order, every item in exactly one part.

``--shard auto`` reads the task index and the array's range from the environment of the
job-array task (the first scheduler whose index variable is set):

* Slurm (``sbatch --array=FIRST-LAST[:STEP]``): ``SLURM_ARRAY_TASK_ID``,
  ``SLURM_ARRAY_TASK_MIN``, ``SLURM_ARRAY_TASK_MAX``, ``SLURM_ARRAY_TASK_STEP`` (absent on
  old versions: then (MAX - MIN) / (COUNT - 1)), ``SLURM_ARRAY_TASK_COUNT``.  Indices may
  start at 0 (``--array=0-9``) or anywhere else; a list that is not an even range
  (``--array=1,3,7``) is refused.
* Grid Engine (``qsub -t FIRST-LAST[:STEP]``): ``SGE_TASK_ID``, ``SGE_TASK_FIRST``,
  ``SGE_TASK_LAST``, ``SGE_TASK_STEPSIZE`` (the value ``undefined`` outside an array job).
* PBS Pro (``qsub -J``): ``PBS_ARRAY_INDEX``; Torque (``qsub -t``): ``PBS_ARRAYID``.  These
  give the index only, so the range is given with the option: ``--shard auto:FIRST-LAST[:STEP]``
  (the range of ``-J`` / ``-t``; it also overrides the range a Slurm or SGE environment gives).

Task FIRST + (K-1) STEP is part K of N = (LAST - FIRST) / STEP + 1.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import NamedTuple

from wormgear_cli.errors import UsageError

#: the index variable of each scheduler, in the order they are looked for, with the variables
#: of the array's range (first, last, step, count; None where the scheduler sets none)
SCHEDULERS = (
    ("Slurm", "SLURM_ARRAY_TASK_ID", ("SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX", "SLURM_ARRAY_TASK_STEP",
                                      "SLURM_ARRAY_TASK_COUNT")),
    ("Grid Engine", "SGE_TASK_ID", ("SGE_TASK_FIRST", "SGE_TASK_LAST", "SGE_TASK_STEPSIZE", None)),
    ("PBS Pro", "PBS_ARRAY_INDEX", None),
    ("Torque", "PBS_ARRAYID", None),
)
#: every index variable, for messages
INDEX_VARIABLES = ", ".join(s[1] for s in SCHEDULERS)
_EXAMPLE = "e.g. 2/8, or auto in a job array"


class Part(NamedTuple):
    """Part ``k`` (1-based) of ``n``; ``source``: where it came from ("" for an explicit K/N,
    else the scheduler and the variables read, for the stderr line)."""

    k: int
    n: int
    source: str = ""

    @property
    def label(self) -> str:
        return f"{self.k}/{self.n}"


def bounds(total: int, k: int, n: int) -> tuple[int, int]:
    """Items [start, stop) of part ``k`` (1-based) of ``n`` contiguous parts of ``total``."""
    return (k - 1) * total // n, k * total // n


def _int(text: str, what: str) -> int:
    try:
        return int(str(text).strip())
    except ValueError:
        raise UsageError(f"--shard auto: {what} is {text!r}, expected a whole number") from None


def _range(text: str) -> tuple[int, int, int]:
    """``FIRST-LAST[:STEP]`` -> (first, last, step)."""
    m = re.fullmatch(r"\s*(\d+)-(\d+)(?::(\d+))?\s*", text)
    if m is None:
        raise UsageError(f'--shard "auto:{text}": expected auto:FIRST-LAST[:STEP], the job array\'s range '
                         "(e.g. auto:0-9 for sbatch --array=0-9 or qsub -J 0-9)")
    first, last, step = int(m[1]), int(m[2]), int(m[3] or 1)
    if last < first or step < 1:
        raise UsageError(f'--shard "auto:{text}": expected FIRST <= LAST and STEP >= 1')
    return first, last, step


def _defined(env: Mapping, name: str | None) -> str | None:
    value = env.get(name) if name else None
    return None if value is None or value.strip() in ("", "undefined") else value


def _from_array(index: int, first: int, last: int, step: int, where: str) -> tuple[int, int]:
    n = (last - first) // step + 1
    if not first <= index <= last or (index - first) % step:
        raise UsageError(f"--shard auto: task index {index} is not in the array {first}-{last}:{step} ({where})")
    return (index - first) // step + 1, n


def _scheduler_range(env: Mapping, names) -> tuple[tuple[int, int, int], str] | None:
    """(first, last, step) from the scheduler's range variables, and the variables read; None
    when they are not set."""
    first_v, last_v, step_v, count_v = names
    first, last = _defined(env, first_v), _defined(env, last_v)
    if first is None or last is None:
        return None
    a, b = _int(first, first_v), _int(last, last_v)
    used = [f"{first_v}={a}", f"{last_v}={b}"]
    step = _defined(env, step_v)
    count = _defined(env, count_v)
    if step is not None:
        s = _int(step, step_v)
        used.append(f"{step_v}={s}")
        if s < 1:
            raise UsageError(f"--shard auto: {step_v}={s}, expected a step of 1 or more")
    elif count is not None and _int(count, count_v) > 1:
        s = max(1, (b - a) // (_int(count, count_v) - 1))
    else:
        s = 1
    if count is not None:
        c = _int(count, count_v)
        used.append(f"{count_v}={c}")
        if (b - a) % s or (b - a) // s + 1 != c:
            raise UsageError(f"--shard auto: the job array is not an even range ({', '.join(used)}; a list such "
                             "as --array=1,3,7?): give --shard K/N, or --shard auto:FIRST-LAST[:STEP]")
    return (a, b, s), ", ".join(used)


def parse(text: str, env: Mapping | None = None) -> Part:
    """``K/N``, ``auto`` or ``auto:FIRST-LAST[:STEP]`` -> :class:`Part`.

    ``env``: the environment (``os.environ``) for ``auto``.  Raises :class:`UsageError` naming
    ``--shard`` for a malformed value, K outside 1..N, or ``auto`` with no job-array index set
    (the message names the variables looked for) or with an index outside the array."""
    text = str(text).strip()
    if text == "auto" or text.startswith("auto:"):
        return _auto(text[5:] if text.startswith("auto:") else None, env or {})
    k, sep, n = text.partition("/")
    try:
        k_i, n_i = int(k), int(n)
    except ValueError:
        raise UsageError(f'--shard "{text}": expected K/N with whole numbers, {_EXAMPLE}') from None
    if not sep or n_i < 1 or not 1 <= k_i <= n_i:
        raise UsageError(f'--shard "{text}": expected K/N with 1 <= K <= N, {_EXAMPLE}')
    return Part(k_i, n_i)


def _auto(given: str | None, env: Mapping) -> Part:
    for name, index_var, range_vars in SCHEDULERS:
        value = _defined(env, index_var)
        if value is None:
            continue
        index = _int(value, index_var)
        if given is not None:
            first, last, step = _range(given)
            k, n = _from_array(index, first, last, step, f"--shard auto:{given}")
            return Part(k, n, f"{name}: {index_var}={index}, range {first}-{last}:{step} from --shard")
        found = _scheduler_range(env, range_vars) if range_vars else None
        if found is None:
            raise UsageError(f"--shard auto: {name} gives the task index ({index_var}={index}) but not the array's "
                             "range; give it as --shard auto:FIRST-LAST[:STEP] (the range of the array, e.g. "
                             "auto:0-9)")
        (first, last, step), used = found
        k, n = _from_array(index, first, last, step, used)
        return Part(k, n, f"{name}: {index_var}={index}, {used}")
    raise UsageError(f"--shard auto: no job-array index in the environment ({INDEX_VARIABLES} are unset); "
                     "run it as a task of a job array, or give --shard K/N")

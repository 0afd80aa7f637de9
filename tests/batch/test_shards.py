"""--shard K/N and --shard auto: the part from a scheduler's job-array variables."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from wormgear_cli.batch.shards import bounds, parse
from wormgear_cli.errors import UsageError


def slurm(task, first, last, step=1, count=None, with_step=True):
    env = {"SLURM_ARRAY_TASK_ID": str(task), "SLURM_ARRAY_TASK_MIN": str(first), "SLURM_ARRAY_TASK_MAX": str(last),
           "SLURM_ARRAY_TASK_COUNT": str(count if count is not None else (last - first) // step + 1)}
    if with_step:
        env["SLURM_ARRAY_TASK_STEP"] = str(step)
    return env


@given(st.integers(0, 10**12), st.integers(1, 1000))
def test_parts_cover_every_item_once_in_order(total, n):
    spans = [bounds(total, k, n) for k in range(1, n + 1)]
    assert spans[0][0] == 0 and spans[-1][1] == total
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:]))
    assert all(0 <= b - a <= -(-total // n) for a, b in spans)


@pytest.mark.parametrize("env, part", [
    (slurm(0, 0, 9), (1, 10)),  # sbatch --array=0-9: task 0 is the first part
    (slurm(9, 0, 9), (10, 10)),
    (slurm(1, 1, 10), (1, 10)),  # 1-based
    (slurm(10, 1, 10), (10, 10)),
    (slurm(5, 1, 7, step=2), (3, 4)),  # --array=1-7:2: tasks 1, 3, 5, 7
    (slurm(5, 1, 7, step=2, with_step=False), (3, 4)),  # no SLURM_ARRAY_TASK_STEP (older Slurm): from the count
    ({"SGE_TASK_ID": "4", "SGE_TASK_FIRST": "2", "SGE_TASK_LAST": "10", "SGE_TASK_STEPSIZE": "2"}, (2, 5)),
    ({"SGE_TASK_ID": "1", "SGE_TASK_FIRST": "1", "SGE_TASK_LAST": "3", "SGE_TASK_STEPSIZE": "1"}, (1, 3)),
])
def test_auto_reads_the_array(env, part):
    got = parse("auto", env)
    assert (got.k, got.n) == part
    assert got.source  # says where it came from


def test_auto_under_a_0_based_slurm_array_says_which_variables():
    got = parse("auto", slurm(2, 0, 3))
    assert got.label == "3/4"
    assert got.source == ("Slurm: SLURM_ARRAY_TASK_ID=2, SLURM_ARRAY_TASK_MIN=0, SLURM_ARRAY_TASK_MAX=3, "
                          "SLURM_ARRAY_TASK_STEP=1, SLURM_ARRAY_TASK_COUNT=4")


@pytest.mark.parametrize("var", ["PBS_ARRAY_INDEX", "PBS_ARRAYID"])
def test_pbs_gives_the_index_and_the_option_the_range(var):
    assert parse("auto:0-9", {var: "0"})[:2] == (1, 10)
    assert parse("auto:1-19:2", {var: "5"})[:2] == (3, 10)
    with pytest.raises(UsageError, match=rf"gives the task index \({var}=3\) but not the array's range; give it "
                                         r"as --shard auto:FIRST-LAST\[:STEP\]"):
        parse("auto", {var: "3"})


def test_sge_outside_an_array_job_is_unset():
    with pytest.raises(UsageError) as exc:
        parse("auto", {"SGE_TASK_ID": "undefined", "SGE_TASK_FIRST": "undefined"})
    assert exc.value.problems == [
        "--shard auto: no job-array index in the environment (SLURM_ARRAY_TASK_ID, SGE_TASK_ID, PBS_ARRAY_INDEX, "
        "PBS_ARRAYID are unset); run it as a task of a job array, or give --shard K/N"]


@pytest.mark.parametrize("text, env, message", [
    ("auto", {}, "no job-array index in the environment"),
    ("auto", {**slurm(3, 1, 7, count=3), "SLURM_ARRAY_TASK_STEP": "1"}, "the job array is not an even range"),
    ("auto", slurm(12, 0, 9), "task index 12 is not in the array 0-9:1"),
    ("auto", {**slurm(0, 0, 9), "SLURM_ARRAY_TASK_ID": "x"}, "SLURM_ARRAY_TASK_ID is 'x', expected a whole number"),
    ("auto:9-0", {"PBS_ARRAYID": "1"}, "expected FIRST <= LAST"),
    ("auto:a-b", {"PBS_ARRAYID": "1"}, "expected auto:FIRST-LAST[:STEP]"),
    ("0/3", {}, 'expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array'),
    ("1/", {}, "expected K/N with whole numbers"),
])
def test_bad_parts_name_the_option(text, env, message):
    with pytest.raises(UsageError) as exc:
        parse(text, env)
    (line,) = exc.value.problems
    assert line.startswith("--shard") and message in line


def test_explicit_range_overrides_the_environment():
    assert parse("auto:0-3", slurm(2, 0, 9))[:2] == (3, 4)


@pytest.mark.parametrize("text, part", [("1/1", (1, 1)), ("3/8", (3, 8)), ("8/8", (8, 8)), (" 2/5 ", (2, 5))])
def test_explicit_parts(text, part):
    got = parse(text, {"SLURM_ARRAY_TASK_ID": "0"})  # an explicit part ignores the environment
    assert (got.k, got.n, got.source, got.label) == (*part, "", f"{part[0]}/{part[1]}")


@pytest.mark.parametrize("env, label", [
    (slurm(6, 2, 8, step=2, with_step=False), "3/4"),  # the step from the count: (8 - 2) / (4 - 1)
    (slurm(5, 5, 5, count=1, with_step=False), "1/1"),  # --array=5
    ({**slurm(5, 5, 5), "SLURM_ARRAY_TASK_STEP": "1"}, "1/1"),
    (slurm(1, 0, 3, with_step=False), "2/4"),
    (slurm(4, 0, 4, step=4, with_step=False), "2/2"),  # --array=0-4:4, two tasks
    (slurm(4, 1, 7, step=3), "2/3"),
    ({"SGE_TASK_ID": "2", "SGE_TASK_FIRST": "1", "SGE_TASK_LAST": "3"}, "2/3"),  # no SGE_TASK_STEPSIZE: 1
])
def test_slurm_step_from_the_count(env, label):
    assert parse("auto", env).label == label


def test_auto_with_a_range_says_so():
    got = parse("auto:2-11:3", {"PBS_ARRAYID": "5"})
    assert (got.label, got.source) == ("2/4", "Torque: PBS_ARRAYID=5, range 2-11:3 from --shard")
    assert parse("auto:5-5", {"PBS_ARRAY_INDEX": "5"}).label == "1/1"


@pytest.mark.parametrize("text, env, line", [
    ("auto:a-b", {"PBS_ARRAYID": "1"},
     '--shard "auto:a-b": expected auto:FIRST-LAST[:STEP], the job array\'s range (e.g. auto:0-9 for sbatch '
     "--array=0-9 or qsub -J 0-9)"),
    ("auto:3-2", {"PBS_ARRAYID": "1"}, '--shard "auto:3-2": expected FIRST <= LAST and STEP >= 1'),
    ("auto:0-9:0", {"PBS_ARRAYID": "1"}, '--shard "auto:0-9:0": expected FIRST <= LAST and STEP >= 1'),
    ("auto:0-9", {"PBS_ARRAYID": "10"}, "--shard auto: task index 10 is not in the array 0-9:1 (--shard auto:0-9)"),
    ("auto:0-8:2", {"PBS_ARRAYID": "3"}, "--shard auto: task index 3 is not in the array 0-8:2 (--shard auto:0-8:2)"),
    ("auto", {"SLURM_ARRAY_TASK_ID": "3"},
     "--shard auto: Slurm gives the task index (SLURM_ARRAY_TASK_ID=3) but not the array's range; give it as "
     "--shard auto:FIRST-LAST[:STEP] (the range of the array, e.g. auto:0-9)"),
    ("auto", {"SLURM_ARRAY_TASK_ID": "3", "SLURM_ARRAY_TASK_MIN": "0"},
     "--shard auto: Slurm gives the task index (SLURM_ARRAY_TASK_ID=3) but not the array's range; give it as "
     "--shard auto:FIRST-LAST[:STEP] (the range of the array, e.g. auto:0-9)"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_COUNT": "3"},
     "--shard auto: the job array is not an even range (SLURM_ARRAY_TASK_MIN=1, SLURM_ARRAY_TASK_MAX=7, "
     "SLURM_ARRAY_TASK_STEP=1, SLURM_ARRAY_TASK_COUNT=3; a list such as --array=1,3,7?): give --shard K/N, or "
     "--shard auto:FIRST-LAST[:STEP]"),
    ("auto", slurm(12, 0, 9),
     "--shard auto: task index 12 is not in the array 0-9:1 (SLURM_ARRAY_TASK_MIN=0, SLURM_ARRAY_TASK_MAX=9, "
     "SLURM_ARRAY_TASK_STEP=1, SLURM_ARRAY_TASK_COUNT=10)"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_STEP": "0"},
     "--shard auto: SLURM_ARRAY_TASK_STEP=0, expected a step of 1 or more"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_MIN": "one"},
     "--shard auto: SLURM_ARRAY_TASK_MIN is 'one', expected a whole number"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_MAX": "x"},
     "--shard auto: SLURM_ARRAY_TASK_MAX is 'x', expected a whole number"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_STEP": "x"},
     "--shard auto: SLURM_ARRAY_TASK_STEP is 'x', expected a whole number"),
    ("auto", {**slurm(3, 1, 7), "SLURM_ARRAY_TASK_COUNT": "x"},
     "--shard auto: SLURM_ARRAY_TASK_COUNT is 'x', expected a whole number"),
    ("auto", {**slurm(3, 1, 7, with_step=False), "SLURM_ARRAY_TASK_COUNT": "x"},
     "--shard auto: SLURM_ARRAY_TASK_COUNT is 'x', expected a whole number"),
    ("auto", {"SLURM_ARRAY_TASK_ID": " ", "SGE_TASK_ID": ""},
     "--shard auto: no job-array index in the environment (SLURM_ARRAY_TASK_ID, SGE_TASK_ID, PBS_ARRAY_INDEX, "
     "PBS_ARRAYID are unset); run it as a task of a job array, or give --shard K/N"),
    ("2/0", {}, '--shard "2/0": expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array'),
    ("1/0", {}, '--shard "1/0": expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array'),
    ("3", {}, '--shard "3": expected K/N with whole numbers, e.g. 2/8, or auto in a job array'),
])
def test_messages(text, env, line):
    with pytest.raises(UsageError) as exc:
        parse(text, env)
    assert exc.value.problems == [line]

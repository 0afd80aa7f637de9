"""``check`` as a library call: the whole per-file verdict (load, analyse, requirements, yield)."""

from __future__ import annotations

from dataclasses import dataclass

from wormgear_cli.analysis.requirements import evaluate


@dataclass(frozen=True)
class FileCheck:
    """The verdict of ``wormgear check`` on one drive file.

    ``valid``: the spec (and its ``[statistics]``) loaded; ``passed``: valid and within every
    requirement (with ``requirements.min_yield``: the estimated yield reaches it);
    ``problems``: the spec's errors, one line each; ``requirements``: one dict per requirement
    (``key``, ``limit_arcsec``, ``value_arcsec``, ``passed``: None when the limit is judged by
    the yield); ``yield_check``: the Monte Carlo yield (:func:`wormgear_cli.tolerance.engine.check_yield`)
    or None; ``findings``: the text lines ``check`` prints for this file; ``warnings``: lines for
    stderr (results beyond a full turn, :func:`wormgear_cli.analysis.sanity.check_angles`).
    """

    file: str
    valid: bool
    passed: bool
    problems: tuple = ()
    requirements: tuple = ()
    yield_check: object = None
    findings: tuple = ()
    warnings: tuple = ()

    def to_dict(self) -> dict:
        """The file's entry of ``check --format json``."""
        out = {"file": self.file, "valid": self.valid, "passed": self.passed, "problems": list(self.problems),
               "requirements": [dict(r) for r in self.requirements]}
        if self.yield_check is not None:
            out["yield"] = self.yield_check.to_dict()
        return out


def check_file(path) -> FileCheck:
    """Load ``path``, analyse it and judge its ``[requirements]`` (what ``wormgear check`` does per file).

    A spec error is not raised: it is returned as an invalid :class:`FileCheck` with the
    error's lines as ``problems``.
    """
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sanity import check_angles
    from wormgear_cli.errors import WormgearError
    from wormgear_cli.spec.loader import load_spec

    name = str(path)
    try:
        spec = load_spec(path)
        result = analyze(spec)
        absurd = check_angles(result.angles, name)  # not finite: a problem; beyond a full turn: a warning
        verdicts = evaluate(spec, result)
        yc, by_yield = None, set()
        if spec.requirements.min_yield is not None:  # a Monte Carlo estimate: imported only then
            from wormgear_cli.tolerance.engine import YIELD_REQUIREMENTS, check_yield

            yc = check_yield(spec)
            by_yield = {f"requirements.{a}_arcsec" for a in YIELD_REQUIREMENTS}  # the limits the yield counts
        elif "statistics" in spec.raw:  # validated even when no yield is required
            from wormgear_cli.tolerance.quantities import statistics_table

            statistics_table(spec)
    except WormgearError as exc:
        return FileCheck(name, False, False, problems=tuple(exc.problems))
    passed, rows, findings = True, [], []
    for v in verdicts:
        row = {"key": v.key, "limit_arcsec": v.limit_arcsec, "value_arcsec": v.value_arcsec, "passed": v.passed}
        if not v.passed and v.key in by_yield:  # with min_yield the sampled limits are judged by the yield
            row["passed"] = None
            findings.append(f"{name}: worst case over {v.key}: limit {v.limit_arcsec:g} arcsec, corner value "
                            f"{v.value_arcsec:.2f} arcsec (judged by requirements.min_yield)")
        elif not v.passed:
            passed = False
            findings.append(f"{name}: FAIL {v.key}: limit {v.limit_arcsec:g} arcsec, value {v.value_arcsec:.2f} arcsec")
        rows.append(row)
    if yc is not None:
        passed = passed and yc.passed
        findings.append(f"{name}: {yc.line()}")
    elif passed:
        n = len(verdicts)
        findings.append(f"{name}: ok ({n} requirement{'s' if n != 1 else ''} met)" if n else
                        f"{name}: ok (valid; no requirements)")
    return FileCheck(name, True, passed, requirements=tuple(rows), yield_check=yc, findings=tuple(findings),
                     warnings=(absurd,) if absurd else ())

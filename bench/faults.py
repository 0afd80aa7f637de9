"""Hand-made faults: slips a tired engineer really makes, one exact text edit each.

Each entry of :data:`FAULTS` is ``name -> Fault(file, old, new, why, tests)``: ``old`` must occur
exactly once in ``wormgear_cli/<file>``; ``tests`` is the everyday selection that should notice
(directories or files under ``tests/``).  ``python bench/mutation.py --faults`` puts each into a
scratch copy, runs its tests and reports killed / survived (docs/development-testing.md, "Hand-made
faults").  Unlike mutmut's syntactic mutants, each of these changes the tool's output on a realistic
input (unit conversions, the standards' rounding, statistics' degrees of freedom, sign conventions).
"""

from __future__ import annotations

from typing import NamedTuple


class Fault(NamedTuple):
    file: str
    old: str
    new: str
    why: str
    tests: tuple[str, ...]


PHYS = ("tests/physics", "tests/drive", "tests/analysis")
ISO1328 = ("tests/physics/test_iso1328.py", "tests/cli/test_grade.py", "tests/physics")
MEAS = ("tests/measurement",)
DIAG = ("tests/diagnosis/test_ranking.py", "tests/diagnosis/test_dof.py", "tests/diagnosis/test_calibration.py",
        "tests/diagnosis/test_mixed.py", "tests/diagnosis/test_inference.py", "tests/diagnosis/test_not_reached.py",
        "tests/diagnosis/test_selection.py")
TOL = ("tests/tolerance",)
COMP = ("tests/compensation", "tests/output")

FAULTS: dict[str, Fault] = {
    # --- physics: the paper's stage models ------------------------------------------------------------
    "worm-te-cos-lead": Fault(
        "physics/worm.py", "(worm_eccentricity**2 + worm_clearance**2) / np.cos(lead_angle) ** 2",
        "(worm_eccentricity**2 + worm_clearance**2) / np.cos(lead_angle)",
        "cos(lambda) not squared in the worm TE half-width", PHYS),
    "worm-te-half": Fault(
        "physics/worm.py",
        "/ np.cos(transverse_pressure_angle) ** 2\n    )\n    return 0.5 * np.sqrt(total)",
        "/ np.cos(transverse_pressure_angle) ** 2\n    )\n    return np.sqrt(total)",
        "the 1/2 of the half-width dropped (full width reported as half)", PHYS),
    "worm-backlash-0126": Fault(
        "physics/worm.py", "0.126 * (worm_profile_error**2", "0.162 * (worm_profile_error**2",
        "transposed digits in the paper's 0.126", PHYS),
    "worm-backlash-36": Fault(
        "physics/worm.py", "/ (36.0 * np.cos(lead_angle) ** 2)", "/ (6.0 * np.cos(lead_angle) ** 2)",
        "36 cos^2 written as 6 cos^2 (the square taken of cos only)", PHYS),
    "worm-backlash-tan-squared": Fault(
        "physics/worm.py", "/ (9.0 * np.tan(transverse_pressure_angle))",
        "/ (9.0 * np.tan(transverse_pressure_angle) ** 2)",
        "the paper's 9 tan(alpha_2) 'corrected' to its square", PHYS),
    "worm-deformation-cos": Fault(
        "physics/worm.py", "deformation = 2.0 * deflection / cos_lam", "deformation = 2.0 * deflection * cos_lam",
        "divide by cos(lambda) written as multiply", PHYS),
    "profile-106": Fault(
        "physics/worm.py", "profile = 1.06 * (worm_profile_error", "profile = 1.6 * (worm_profile_error",
        "1.06 typed 1.6", PHYS),
    "pitch-arc-factor": Fault(
        "physics/spur.py", "    return 2.0 * arc / (module * teeth)", "    return arc / (module * teeth)",
        "arc over the pitch diameter instead of the radius (factor 2)", PHYS),
    "gear-backlash-abs": Fault(
        "physics/spur.py", "np.tan(pressure_angle) * np.abs(np.sin(phi)) + 2.0 * deflection",
        "np.tan(pressure_angle) * np.sin(phi) + 2.0 * deflection",
        "|sin phi| lost: backlash goes negative over half a turn", PHYS),
    "gear-deformation-sign": Fault(
        "physics/spur.py", "return deflection * np.sin(pressure_angle + lam1) / gear_radius",
        "return deflection * np.sin(pressure_angle - lam1) / gear_radius",
        "sign of the eccentricity angle in the load term", PHYS),
    "thermal-sign": Fault(
        "physics/thermal.py", "            - (worm_radius * worm_expansion * worm_dt + wheel_radius",
        "            + (worm_radius * worm_expansion * worm_dt + wheel_radius",
        "members' growth added to the housing's instead of subtracted", PHYS),
    "thermal-worm-radius": Fault(
        "physics/thermal.py", "worm_radius = wp.worm.starts * wp.module / math.tan(wp.lead_angle) / 2.0",
        "worm_radius = wp.worm.starts * wp.module / math.tan(wp.lead_angle)",
        "worm pitch diameter used as its radius", PHYS),
    "effect-backlash-half": Fault(
        "physics/effects.py", "    return -s.direction * db / 2.0", "    return -s.direction * db",
        "the thermal backlash's half per direction dropped", PHYS + DIAG),
    "effect-base-radius": Fault(
        "physics/effects.py", "    return eccentricity / g.output_base_radius * np.sin(s.theta + phase)",
        "    return eccentricity / g.output_pitch_radius * np.sin(s.theta + phase)",
        "pitch radius for the base radius in the output runout", PHYS),
    "units-arcsec": Fault(
        "units.py", '    "arcsec": math.pi / (180.0 * 3600.0),', '    "arcsec": math.pi / (180.0 * 360.0),',
        "3600 typed 360", PHYS),
    "paper-arcmin": Fault(
        "units.py", "PAPER_ARCMIN_CONSTANT = 2.0 * 180.0 * 60.0 / (math.pi * 1000.0)",
        "PAPER_ARCMIN_CONSTANT = 180.0 * 60.0 / (math.pi * 1000.0)",
        "the paper's 6.875 constant off by a factor 2", PHYS),
    "budget-rss": Fault(
        "analysis/budget.py", "rss = s_static + math.sqrt(sum(ln.amplitude ** 2 for ln in periodic))",
        "rss = s_static + math.sqrt(sum(ln.amplitude ** 2 for ln in all_lines))",
        "static lines root-sum-squared with the periodic ones", ("tests/analysis",)),
    "budget-phasor-sign": Fault(
        "analysis/budget.py", "phasors[sine[1]] = phasors.get(sine[1], 0j) + sine[0] * cmath.exp(1j * psi)",
        "phasors[sine[1]] = phasors.get(sine[1], 0j) + sine[0] * cmath.exp(-1j * psi)",
        "phasor conjugated: sources of one order added at the wrong relative phase", ("tests/analysis",)),
    "budget-peak-refine": Fault(
        "analysis/budget.py", "t = theta[k] + 0.5 * step * (y0 - y2) / den", "t = theta[k] + step * (y0 - y2) / den",
        "parabolic peak refinement without its 1/2", ("tests/analysis",)),
    "budget-sines-row-start": Fault(
        "analysis/budget.py", "        starts = (first + _SINE_ROW * np.arange(rows)) * self.step\n",
        "        starts = (first + _SINE_ROW * np.arange(1, rows + 1)) * self.step\n",
        "the peak search's rows start one row late (every sample's phase shifted)", PHYS),
    "budget-sines-real-part": Fault(
        "analysis/budget.py", "        return (at @ self.turn).imag.reshape(-1)[:count]\n",
        "        return (at @ self.turn).real.reshape(-1)[:count]\n",
        "the phasor sum's real part taken (a cosine for the sine: the peak at the wrong phase)", PHYS),
    "table-fit-natural-width": Fault(
        "cli/common.py", "table).maximum <= width:", "table).maximum <= width + 2:",
        "a table two columns wider than the terminal taken as fitting (a number cut at the edge)",
        ("tests/cli/test_rendering.py",)),
    # --- ISO 1328 -------------------------------------------------------------------------------------
    "iso1328-step": Fault(
        "physics/iso1328.py", "    return math.sqrt(2.0) ** (grade - 5)", "    return math.sqrt(2.0) ** (grade - 4)",
        "class step counted from grade 4", ISO1328),
    "iso1328-fpt": Fault(
        "physics/iso1328.py", "f_pt = (0.001 * d + 0.4 * m + 5.0) * s", "f_pt = (0.001 * d + 0.4 * m + 0.5) * s",
        "5.0 typed 0.5 in f_pT", ISO1328),
    "iso1328-round-halves": Fault(
        "physics/iso1328.py", "return round(math.floor(value_um / step + 0.5 + 1e-9) * step, 1)",
        "return round(round(value_um / step) * step, 1)",
        "Python's round (halves to even) for the standard's halves-up", ISO1328),
    "iso1328-round-band": Fault(
        "physics/iso1328.py", "    elif value_um >= 5.0:\n        step = 0.5",
        "    elif value_um > 5.0:\n        step = 0.5",
        "5 um itself rounded to 0.1 um instead of 0.5 um", ISO1328),
    "iso1328-frt-rounded": Fault(
        "physics/iso1328.py", "rt(f_hb), rt(f_fb), rt(math.hypot(f_hb, f_fb)), rt(0.9 * f_p))",
        "rt(f_hb), rt(f_fb), rt(math.hypot(f_hb, f_fb)), rt(0.9 * rt(f_p)))",
        "F_rT from the rounded F_pT", ISO1328),
    "iso1328-range-bound": Fault(
        "physics/iso1328.py", "        if value <= hi:\n            return math.sqrt(lo * hi)",
        "        if value < hi:\n            return math.sqrt(lo * hi)",
        "a value on a range's upper bound put in the next range", ISO1328),
    "iso1328-part2-step": Fault(
        "physics/iso1328.py", "    step = 2.0 ** (0.5 * (grade - 5))", "    step = 2.0 ** (0.5 * (grade - 4))",
        "ISO 1328-2 step counted from Q4", ISO1328),
    # --- ISO 230-2 ------------------------------------------------------------------------------------
    "iso230-ddof": Fault(
        "measurement/iso230.py", "s = np.sqrt(ss / (n - 1.0))", "s = np.sqrt(ss / n)",
        "population standard deviation for the sample one", MEAS),
    "iso230-R-4s": Fault(
        "measurement/iso230.py", "    r_up = 4.0 * s_up\n", "    r_up = 2.0 * s_up\n",
        "unidirectional repeatability 2 s instead of 4 s", MEAS),
    "iso230-R-bi": Fault(
        "measurement/iso230.py", "2.0 * s_up + 2.0 * s_dn + np.abs(reversal)", "2.0 * s_up + 2.0 * s_dn + reversal",
        "|B_i| without the absolute value", MEAS),
    "iso230-A-2s": Fault(
        "measurement/iso230.py", "return _span(*(m + 2.0 * s for m, s in zip(means, ss)), *(m - 2.0 * s for m, s",
        "return _span(*(m + 3.0 * s for m, s in zip(means, ss)), *(m - 3.0 * s for m, s",
        "accuracy A with 3 s (the old VDI habit) instead of 2 s", MEAS),
    "iso230-B-mean": Fault(
        "measurement/iso230.py", "B, B_signed, B_mean = np.abs(signed), signed, np.mean(b, axis=1)",
        "B, B_signed, B_mean = np.abs(signed), signed, np.mean(np.abs(b), axis=1)",
        "mean reversal of the magnitudes (sign lost)", MEAS),
    "iso230-mean-bi": Fault(
        "measurement/iso230.py", "    mean_bi = 0.5 * (mean_up + mean_dn)", "    mean_bi = 0.5 * (mean_up - mean_dn)",
        "mean bidirectional deviation with a minus", MEAS),
    # --- readers --------------------------------------------------------------------------------------
    "reader-time-min": Fault(
        "measurement/readers/table.py", '"ms": 1e-3, "min": 60.0,', '"ms": 1e-3, "min": 1.0 / 60.0,',
        "minutes divided instead of multiplied", MEAS),
    "reader-direction-01": Fault(
        "measurement/readers/values.py", "            if v in (1.0, -1.0):\n                value[i] = v",
        "            if v in (1.0, -1.0, 0.0):\n                value[i] = 1.0 if v else -1.0",
        "a 0/1 direction column accepted, 1 and 0 read as +1/-1 and -1 as -1", MEAS),
    "reader-cw-sign": Fault(
        "measurement/readers/values.py",
        "value[i], rotation[i] = (1.0 if tok in CLOCKWISE_WORDS else -1.0), True",
        "value[i], rotation[i] = (-1.0 if tok in CLOCKWISE_WORDS else 1.0), True",
        "CW and CCW swapped before orienting", MEAS),
    # --- measure: orders and their uncertainty --------------------------------------------------------
    "phase-se-missing-square": Fault(
        "measurement/harmonics.py",
        "var_phase = np.where(amp > 0, (b * b * va + a * a * vb - 2 * a * b * cab) / amp**4",
        "var_phase = np.where(amp > 0, (b * b * va + a * a * vb - 2 * a * b * cab) / amp**2",
        "phase variance divided by A^2 instead of A^4 (the delta method's gradient not squared)", MEAS),
    "phase-se-cov-sign": Fault(
        "measurement/harmonics.py", "(b * b * va + a * a * vb - 2 * a * b * cab) / amp**4",
        "(b * b * va + a * a * vb + 2 * a * b * cab) / amp**4",
        "sign of the covariance term in the phase variance", MEAS),
    "amp-se-cov-sign": Fault(
        "measurement/harmonics.py", "(a * a * va + b * b * vb + 2 * a * b * cab) / amp**2",
        "(a * a * va + b * b * vb - 2 * a * b * cab) / amp**2",
        "sign of the covariance term in the amplitude variance", MEAS),
    "order-fit-dof": Fault(
        "measurement/harmonics.py", "        dof = n - rank[i]\n", "        dof = n - rank[i] + 1\n",
        "residual degrees of freedom off by one (the offset not counted)", MEAS),
    "orders-joint-dof": Fault(
        "measurement/orders.py", "    dof = sums.n - gram.shape[0]\n", "    dof = sums.n - gram.shape[0] // 2\n",
        "measure's joint fit counts only the common-mode columns", MEAS),
    "phase-convention": Fault(
        "measurement/harmonics.py", "    phase = np.arctan2(a, b)\n", "    phase = np.arctan2(b, a)\n",
        "phase of A cos instead of A sin", MEAS),
    "scan-addition-sign": Fault(
        "measurement/dominant.py", "            cos -= np.multiply(sa, sb, out=work)\n",
        "            cos += np.multiply(sa, sb, out=work)\n",
        "cos(a + b) written with the sign of cos(a - b) in the scan's fast grid", MEAS),
    "scan-grid-unchecked": Fault(
        "measurement/dominant.py",
        "<= SPLIT_ULPS * np.finfo(float).eps * float(np.max(np.abs(orders)))",
        "<= SPLIT_ULPS * float(np.max(np.abs(orders)))",
        "the fast grid's check of evenly spaced orders without its eps (any orders pass)", MEAS),
    "refine-harmonic-recurrence": Fault(
        "measurement/dominant.py", "            c, s, h = c * c1 - s * s1, s * c1 + c * s1, h + 1\n",
        "            c, s, h = c * c1 - s * s1, s * c1 - c * s1, h + 1\n",
        "sin of the next harmonic with the wrong sign (the refinement's harmonics)", MEAS),
    # --- diagnosis statistics -------------------------------------------------------------------------
    "rank-by-F": Fault(
        "diagnosis/scoring.py", "return (0, -w.F * w.q) if scores[n].p_adj < alpha",
        "return (0, -w.F) if scores[n].p_adj < alpha",
        "significant candidates ranked by F instead of chi^2 = F q", DIAG),
    "rank-by-p": Fault(
        "diagnosis/scoring.py", "return (0, -w.F * w.q) if scores[n].p_adj < alpha",
        "return (0, w.p) if scores[n].p_adj < alpha",
        "significant candidates ranked by p", DIAG),
    "satterthwaite-2": Fault(
        "diagnosis/mixed.py", "    return 2.0 * variances**2 / np.maximum(", "    return variances**2 / np.maximum(",
        "Satterthwaite's 2 dropped", DIAG),
    "max-effects-off-by-one": Fault(
        "diagnosis/selection.py", "return Stop(StopReason.MAX_EFFECTS, best=best, max_effects=opt.max_effects)",
        "return None if len(run.accepted) <= opt.max_effects else Stop(StopReason.MAX_EFFECTS, best=best, "
        "max_effects=opt.max_effects)",
        "--max-effects allows one more effect", DIAG),
    "same-order-threshold": Fault(
        "diagnosis/inference.py", "factor = 1.0 + t_ppf(0.975, dof) ** 2 / dof",
        "factor = 1.0 + t_ppf(0.975, dof) / dof",
        "profile threshold with t instead of t^2", DIAG),
    "same-order-threshold-95": Fault(
        "diagnosis/inference.py", "factor = 1.0 + t_ppf(0.975, dof) ** 2 / dof",
        "factor = 1.0 + t_ppf(0.95, dof) ** 2 / dof",
        "one-sided 95 % t for the two-sided range", DIAG),
    # --- tolerance ------------------------------------------------------------------------------------
    "normal-6cp": Fault(
        "tolerance/distributions.py", "    sigma = width / (6.0 * cp_e)", "    sigma = width / (3.0 * cp_e)",
        "tolerance width taken as 3 sigma instead of 6 sigma", TOL),
    "normal-cpk-shift": Fault(
        "tolerance/distributions.py", "mu = 0.5 * (low + high) + 0.5 * width * (1.0 - cpk_e / cp_e)",
        "mu = 0.5 * (low + high) - 0.5 * width * (1.0 - cpk_e / cp_e)",
        "cpk shifts the mean towards the lower limit", TOL),
    "rayleigh-3c": Fault(
        "tolerance/distributions.py", "    return high / (3.0 * c)", "    return high / (2.0 * c)",
        "Rayleigh sigma at T/2c", TOL),
    "yield-level": Fault(
        "tolerance/statistics.py", 'proportion_ci(confidence_level=level, method="exact")',
        'proportion_ci(confidence_level=level, method="wilson")',
        "Wilson interval reported as Clopper-Pearson", TOL),
    "percentile-type": Fault(
        "tolerance/statistics.py", "        h = (n - 1) * float(p) / 100.0\n", "        h = n * float(p) / 100.0\n",
        "percentile rank n q instead of (n - 1) q", TOL),
    "sobol-msw": Fault(
        "tolerance/statistics.py", "            msw = max(sst - ssb, 0.0) / (n - b)",
        "            msw = max(sst - ssb, 0.0) / n",
        "within-bin mean square over n", TOL),
    # --- simulation and synth -------------------------------------------------------------------------
    "synth-drift-ramp": Fault(
        "analysis/synth.py", "        frac = (np.arange(n) % per) / max(per - 1, 1)",
        "        frac = (np.arange(n) % per) / per",
        "the run drift's ramp never reaches its full value", ("tests/analysis", "tests/cli/test_synth.py")),
    "sweep-grid-inclusive": Fault(
        "analysis/sweep.py", "        return np.linspace(self.start, self.stop, self.n)",
        "        return np.linspace(self.start, self.stop, self.n, endpoint=False)",
        "sweep grid stops short of STOP", ("tests/analysis", "tests/cli/test_sweep.py")),
    # --- this stop's changes: the phased peak, the correction's prediction, the PEC and table checks ----
    "peak-fast-bound-dropped": Fault(
        "analysis/budget.py", "    return high + bound, low - bound", "    return high, low",
        "orders past the sampled ones left out of the phased peak instead of bounded",
        ("tests/analysis/test_budget.py",)),
    "peak-block-edge": Fault(
        "analysis/budget.py", "    k = 1 + int(np.argmax(y[1:-1]))", "    k = int(np.argmax(y[1:-1]))",
        "the best sample of a block taken one sample off (the neighbours' index shift forgotten)",
        ("tests/analysis/test_budget.py",)),
    "predict-remainder-unscaled": Fault(
        "compensation/predict.py", "    return means * math.sqrt(remainder_var / mean_square)",
        "    return means",
        "the cross-validated cell means taken as the remainder with their noise left in",
        ("tests/compensation", "tests/cli/test_compensate.py")),
    "predict-own-noise-dropped": Fault(
        "compensation/predict.py", "    return missed, within * h", "    return missed, 0.0",
        "the table's own noise left out of a repeat test", ("tests/compensation", "tests/cli/test_compensate.py")),
    "pec-rows-per-term": Fault(
        "workflows/compensate.py", "    if told < terms or rows < 2 * terms:", "    if told < terms or rows < terms:",
        "a PEC curve accepted with as many terms as rows", ("tests/cli/test_compensate.py",)),
    "table-range-full-turn": Fault(
        "workflows/compensate.py", "    if coverage(theta).full_turn:", "    if not coverage(theta).full_turn:",
        "the default table span swapped: a partial arc gets 0-360",
        ("tests/cli/test_compensate.py", "tests/workflows/test_compensate.py")),
    "pec-phase-gaps-ignored": Fault(
        "workflows/compensate.py", "    if empty:\n", "    if empty > bins // 2:\n",
        "a PEC record accepted while half the worm cycle is unread", ("tests/cli/test_compensate.py",)),
    "pec-left-curve-harmonics-only": Fault(
        "compensation/pec.py", "    top = max(2 * len(curve.harmonics), LEFT_HARMONICS)",
        "    top = max(len(curve.harmonics), 1)",
        "the PE left read only at the harmonics the curve carries", ("tests/cli/test_compensate.py",)),
    "table-one-direction-means": Fault(
        "compensation/model.py", "(np.ones(d.shape, dtype=bool),) * 2", "(d > 0, d < 0)",
        "one direction's per-target means put into its own column only", ("tests/cli/test_compensate.py",)),
    "pec-undetermined-threshold": Fault(
        "workflows/compensate.py", "PEC_UNDETERMINED = 0.5", "PEC_UNDETERMINED = 5.0",
        "a PEC curve accepted while its standard error is twice the curve", ("tests/cli/test_compensate.py",)),
    "pec-se-without-drift": Fault(
        "compensation/pec.py", "    x, scale, drifts = _design(th, np.asarray(run), ords, degree)",
        "    x, scale, drifts = _design(th, np.asarray(run), ords, 0)",
        "the curve's standard error computed as if the sessions had no drift", ("tests/cli/test_compensate.py",)),
    "sweep-figures-torque-scale": Fault(
        "analysis/sweep.py", "ref.gear_force * (ref.r2 / r2 if torque", "ref.gear_force * (r2 / ref.r2 if torque",
        "a design's swept-stage force scaled the wrong way under the torque hold", ("tests/cli/test_sweep.py",)),
    "sweep-figures-upstream-unscaled": Fault(
        "analysis/sweep.py", "_load(up) * (ref.i / ratio if torque else 1.0)", "_load(up)",
        "the stages before the swept one keep the spec's loads under the torque hold", ("tests/cli/test_sweep.py",)),
    "output-path-dot-ending": Fault(
        "cli/common.py", '_FOLDER_ENDING = re.compile(r"(?<=.)/(\\.{0,2}/*)?$")',
        '_FOLDER_ENDING = re.compile(r"(?<=.)/+$")',
        "only a trailing / read as a folder: out/. (which the path object drops) writes a file named out",
        ("tests/files/test_paths.py",)),
    "report-path-unchecked": Fault(
        "cli/compensate.py", 'show_default=False, click_type=output_path_type("--report", "report.json"))',
        "show_default=False)", "one output option (--report) left without the output path type",
        ("tests/files/test_paths.py",)),
    "compensate-harmonics-given-as-not-default": Fault(
        "workflows/compensate.py", "    if options.harmonics is not None and not is_pec and options.drive is None:",
        "    if options.harmonics not in (None, DEFAULT_HARMONICS) and not is_pec and options.drive is None:",
        "--harmonics 3 (the default's value) taken as not given: a table without --drive ignores it",
        ("tests/cli/test_compensate.py",)),
    "api-figures-truthy": Fault(
        "api.py", '    figures = _flag("figures", figures)', "    figures = bool(figures)",
        'api.sweep(figures="no") read as True',
        ("tests/test_api.py::test_api_arguments_that_would_be_ignored_or_misread_are_refused",)),
    "api-choice-case": Fault(
        "api.py", "isinstance(value, str) and value.lower() == c.lower()", "value == c",
        'hold="TORQUE" refused by the API while the CLI takes --hold TORQUE',
        ("tests/test_api.py::test_sweep_hold_in_any_case_as_on_the_command_line",)),
    "sweep-axis-range-unchecked": Fault(
        "analysis/sweep.py", "    if not lo <= low <= high <= hi:", "    if not lo <= low:",
        "only the low end of an (i, l) axis checked: --i up to 1e300 gives inf rows and numpy warnings",
        ("tests/cli/test_sweep.py",)),
    "drive-check-only-in-analyze": Fault(
        "cli/common.py", "    check_drive(spec, str(path))\n    return spec", "    return spec",
        "the impossible-drive check left to analyze and check: tolerance and simulate print 44 223 deg of backlash",
        ("tests/analysis/test_sanity.py",)),
    "header-unit-underscore-unread": Fault(
        "measurement/readers/header.py", "for form in (_SLASH, _IN, _UNDERSCORE):", "for form in (_SLASH, _IN):",
        "a unit written as a last '_' suffix (error_mm, error_deg) not recognised: read as arcsec",
        ("tests/measurement/test_readers.py",)),
    "mrad-as-urad": Fault(
        "units.py", '    "mrad": 1e-3,', '    "mrad": 1e-6,',
        "a milliradian taken for a microradian", ("tests/measurement/test_readers.py",)),
    "count-lines-opens-fifo": Fault(
        "files.py",
        "        if not stat.S_ISREG(os.stat(path).st_mode):\n            return None\n        with open(path, \"rb\"",
        "        with open(path, \"rb\"",
        "the memory check's line count opens a FIFO and closes it unread: measure loses the data and waits",
        ("tests/cli/test_measure.py",)),
    "guidelog-time-bound-only": Fault(
        "measurement/guidelog.py", "if i + 2 < n and t[i + 2] >= t[i]:  # a dip",
        "if i + 2 < n and t[i + 2] <= t[i]:  # a dip",
        "a guide log's Time cell out of order between two in order is read as a clock restart (a new session)",
        ("tests/measurement/test_guidelog.py",)),
    "guidelog-spike-run-ignored": Fault(
        "measurement/guidelog.py", "SPIKE_ROWS = 20", "SPIKE_ROWS = 0",
        "a run of corrupt Time cells read as a clock restart", ("tests/measurement/test_guidelog.py",)),
    "header-canonical-not-preferred": Fault(
        "measurement/readers/header.py", "            elif header[index[canon]].strip().lower() == canon.lower():",
        "            elif False:",
        "angle_deg beside angle_rad refused as two columns for one name",
        ("tests/measurement/test_reader_formats.py",)),
    "guide-orders-one-period": Fault(
        "workflows/guidelog.py", "        order = min(k for k in orders if _resolvable(k, longest / 2.0, nyquist))",
        "        order = min(k for k in orders if _resolvable(k, longest, nyquist))",
        "an order with one period in a session taken as the worm's", ("tests/cli/test_measure_guidelog.py",)),
}

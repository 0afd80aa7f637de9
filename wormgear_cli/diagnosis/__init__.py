"""Diagnosis: where a drive model and a measurement disagree, and which
catalogue effect the model lacks (the core of ``wormgear diagnose``).

Pure numpy (scipy for distribution functions, imported lazily); no I/O, no
typer, no rich.  Angles are handled in arcsec inside this package (the
measured error and every model column are divided by
:data:`wormgear_cli.units.ARCSEC` once) so the statistics work on numbers of
order one.

Layout (one topic per module; this ``__init__`` re-exports the public names)
-------------------------------------------------------------------------
``runs``        passes, runs, cells, what varies (DataInfo)
``design``      orthonormal bases and projections of design columns
``mixed``       GLS/REML from sufficient statistics, Wald tests, Satterthwaite
                and containment df, the cell-means test, F and t functions
``phases``      the spec's periodic sources and the phase/offset fit
``candidates``  catalogue effects as columns; observability, replication,
                physical range, aliasing by the target spacing
``scoring``     one selection step: every candidate tested against the model
``selection``   forward selection (:func:`diagnose`), stop reasons, Diagnosis
``inference``   tests and intervals of the named effects in the final model
``scan``        structure left in the residual that no catalogue effect explains
``residuals``   views of the residual: gap, orders, trends, noise floor
``augment``     the augmented spec (TOML)
``report``      verdict, status of the candidates, the JSON document
``thresholds``  the decision constants

Model
-----
For row i (output angle theta_i [rad], direction d_i = +/-1, load [N m],
temperature [degC], time [s]) the measured error y_i [arcsec] is

    y_i = m(theta_i, d_i, ...; psi) + c + sum_j beta_j x_ij + u_run(i) + v_pass(i) + e_i

* m: the spec's model (:func:`wormgear_cli.analysis.simulate.simulate`) with the
  phases psi of its periodic sources fitted; their amplitudes stay as
  specified (a drawing knows sizes, not the angular position they were
  assembled at);
* c: ONE zero offset for the whole measurement (an offset per run would
  swallow a thermal drift);
* x_j, beta_j: the columns of catalogue effects added by the selection
  (linear in their physical parameter, or in its reciprocal for a
  stiffness, or a sin/cos pair for a periodic effect);
* noise: nested random intercepts, u ~ N(0, s_run^2) per run (both
  directions of a run share it) and v ~ N(0, s_pass^2) per pass (one run in
  one direction), plus white e ~ N(0, s_white^2).  Estimated by REML;
  fixed effects by generalised least squares (GLS).  Without a ``run``
  column a pass is a block of consecutive rows in one direction.

Everything that depends on the variance ratios g_p = s_pass^2/s_white^2,
g_r = s_run^2/s_white^2 is computed from sufficient statistics (X'X, X'y,
y'y and per-pass sums) with the closed-form inverse of the nested
covariance, so REML and GLS cost O(passes * k^2) per evaluation whatever
the number of rows.

Selection (forward, over groups of columns)
-------------------------------------------
1. Fit psi and c: deterministic starts, an exhaustive grid over the phases
   of each shaft's sources, Levenberg-Marquardt polish, then GLS with REML
   variance components on every row.
2. For every catalogue effect the spec lacks: check it is observable (the
   signal it needs varies, its order is not aliased by the target spacing,
   its columns are not absorbed by the offset or the effects already in),
   then a Wald F-test of its columns given the current model, variance
   components re-estimated by REML under the alternative, denominator
   degrees of freedom by Satterthwaite's approximation (Fai-Cornelius for
   two columns) capped by the containment df of the level the effect varies
   at, so effects that change only between runs are judged against
   run-to-run scatter.  A signature that depends only on angle and direction
   must also pass the same test on the per-target cell means (lack of fit
   as error: a misfit repeated in every run is not replication).  An effect
   on the order of spec sources with fitted phases is tested by refitting
   the phases with it (only content those fixed-size sources cannot reach
   counts).  p-values are multiplied by the number of candidates tested
   (Bonferroni).
3. Among the significant candidates the one with the largest Wald
   chi-square is accepted only if its parameter lies inside the catalogue's
   physical range, no other significant candidate has (nearly) the same
   signature (canonical correlation >= 0.99) and it is stable: best in at
   least 60 % of resamples of whole runs (cluster bootstrap, fixed seed).
   Otherwise the selection stops and says why.
4. Refit everything (phases, offset, accepted effects, variance
   components).  If the RMS residual does not shrink, the candidate is
   rejected and the selection stops (a significant GLS test whose fit makes
   the gap larger follows structure that is not its signature, the random
   effects absorbing what it gets wrong).  Otherwise repeat.

With fewer than MIN_RUNS runs no variance between runs or passes is
estimated (the noise is taken as white); candidates whose columns vary
mainly between passes, and thermal ones in a monotonic warm-up, are
"untestable", and the others are tested with their columns as nuisance.

A candidate that stops the selection narrowly (adjusted p < NEAR_FACTOR
alpha) or at the --max-effects limit is refitted: if it removes at least
NEAR_SHARE of the remaining mean-square gap it is reported as likely, and
each named effect's interval is widened to cover its interval in that
larger model.  An effect on the order of spec sources with fitted phases
gets the range of sizes that fit as well (profile of the GLS cost) instead
of an interval.

What is left is scanned for structure no catalogue effect explains:
harmonics at the drive's physical orders and low integer orders (common
and differential mode) and trends against temperature, load and time, and
a mean reversal change (each a Wald test, with the cell-means check for
orders; Bonferroni over the scan).  The RMS residual is compared with the
noise floor (point-to-point noise within passes plus the fitted scatter
between passes and runs): above EXCESS_FACTOR times it, it is reported.

Sources: REML and the nested-intercept GLS are textbook linear mixed model
results (Harville 1977; Searle, Casella & McCulloch 1992); the degrees of
freedom follow Satterthwaite (1946) and Fai & Cornelius (1996); the
F and t distributions are scipy.special's fdtrc and stdtrit.
"""

from wormgear_cli.diagnosis.candidates import (
    REPLICATION_REMEDY,
    UNPHYSICAL_HINT,
    Candidate,
    CandidateKind,
    candidate,
    candidate_params,
    jointly_fittable_orders,
    needs_problem,
    physical_problem,
    replication_problem,
    unaliased_orders,
)
from wormgear_cli.diagnosis.inference import Accepted, Found, augmented_params
from wormgear_cli.diagnosis.mixed import (
    CellTester,
    Cross,
    VarFit,
    Wald,
    containment_df,
    contrast_df,
    f_sf,
    reml,
    t_ppf,
    wald,
)
from wormgear_cli.diagnosis.phases import FitContext, ModelFit, PhaseSource, fit_model, phase_sources, sources_total
from wormgear_cli.diagnosis.report import DiagnoseResult, augmented_toml, report, run_diagnose
from wormgear_cli.diagnosis.residuals import (
    gap_summary,
    iso_figures,
    noise_floor,
    order_table,
    order_tables,
    short_term_noise,
    versus,
)
from wormgear_cli.diagnosis.runs import (
    Cells,
    DataInfo,
    Groups,
    cell_level,
    data_info,
    make_cells,
    make_groups,
    time_restarts,
)
from wormgear_cli.diagnosis.scoring import Score, ScoreStatus, Step
from wormgear_cli.diagnosis.selection import Diagnosis, Stop, StopReason, diagnose
from wormgear_cli.diagnosis.thresholds import (
    EXCESS_FACTOR,
    INDISTINGUISHABLE,
    JOINT_MIN_SINGULAR_VALUE,
    MIN_HELD_TOLERANCE,
    MIN_RUNS,
    MIN_SCAN_SHARE,
    MIN_STABILITY,
    MIN_TEMPERATURE_RANGE,
    MIN_TOLERANCE,
    MONOTONIC,
    NEAR_FACTOR,
    NEAR_SHARE,
    NEARLY,
)
from wormgear_cli.units import ARCSEC

__all__ = [
    "ARCSEC", "Accepted", "DiagnoseResult", "Candidate", "CandidateKind", "CellTester", "Cells", "Cross",
    "DataInfo", "Diagnosis", "EXCESS_FACTOR", "FitContext", "Found", "Groups", "INDISTINGUISHABLE",
    "JOINT_MIN_SINGULAR_VALUE", "MIN_HELD_TOLERANCE", "MIN_RUNS", "MIN_SCAN_SHARE", "MIN_STABILITY",
    "MIN_TEMPERATURE_RANGE", "MIN_TOLERANCE", "MONOTONIC", "ModelFit", "NEARLY", "NEAR_FACTOR", "NEAR_SHARE",
    "PhaseSource", "REPLICATION_REMEDY", "Score", "ScoreStatus", "Step", "Stop", "StopReason",
    "UNPHYSICAL_HINT", "VarFit", "Wald", "augmented_params", "augmented_toml", "candidate",
    "candidate_params", "cell_level", "containment_df", "contrast_df", "data_info", "diagnose", "f_sf",
    "fit_model", "gap_summary", "iso_figures", "jointly_fittable_orders", "make_cells", "make_groups",
    "needs_problem", "noise_floor", "order_table", "order_tables", "phase_sources", "physical_problem",
    "reml", "replication_problem", "report", "unaliased_orders", "run_diagnose", "short_term_noise",
    "sources_total", "t_ppf", "time_restarts", "versus", "wald",
]

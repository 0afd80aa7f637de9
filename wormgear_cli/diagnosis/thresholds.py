"""Decision thresholds of the diagnosis (one place for every tuning constant)."""

from __future__ import annotations

#: canonical correlation above which two signatures cannot be told apart
INDISTINGUISHABLE = 0.99
#: ... and above which they are reported as nearly so
NEARLY = 0.95
#: fraction of a candidate's columns left after projecting out the model below which it is unobservable
MIN_TOLERANCE = 1e-6
#: share of resamples in which an accepted effect must come out best
MIN_STABILITY = 0.6
#: smallest temperature range [K] that lets thermal effects be seen
MIN_TEMPERATURE_RANGE = 0.1
#: fewest runs from which scatter between runs and passes can be estimated
MIN_RUNS = 3
#: |correlation| of temperature and time above which a warm-up is called monotonic
MONOTONIC = 0.95
#: a candidate not significant at alpha but below this multiple of it is reported as a likely effect ...
NEAR_FACTOR = 5.0
#: ... when adding it would remove at least this share of the remaining mean-square gap
NEAR_SHARE = 0.05
#: a residual RMS above this multiple of the noise floor is reported as unexplained
EXCESS_FACTOR = 2.0
#: smallest singular value of the column-normalised design [1, cos, sin, ...] at the distinct angles for
#: orders to be fitted together in the order table (sv^2 is the smallest eigenvalue of the unit-diagonal Gram)
JOINT_MIN_SINGULAR_VALUE = 0.05
#: share of a harmonic direction's sum of squares that must survive projection on the model for the residual scan
#: to test it (below, its estimate is a tiny remainder blown up: a smooth drift over a short span becomes many
#: large "harmonics")
MIN_SCAN_SHARE = 0.05
#: tolerance (share left after projecting out the model) an unexplained order needs to be held in the model the
#: candidates are tested against
MIN_HELD_TOLERANCE = 0.5
#: the spec is taken not to describe the data when, at an order its sources produce or in the mean reversal,
#: spec and data differ by at least this factor ...
MISMATCH_RATIO = 3.0
#: ... and by at least this multiple of the repeatability (per point)
MISMATCH_NOISE = 5.0
#: a data/spec size ratio within this factor of a unit ratio (e.g. 1/60) is reported as a likely unit mix-up
UNIT_RATIO_TOLERANCE = 1.5

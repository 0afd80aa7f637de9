"""Statistical tolerance analysis (core of ``wormgear tolerance``).

Each Monte Carlo sample is one built drive: every toleranced key of the spec
drawn from a distribution fitting its nature, truncated at its tolerance
(parts out of tolerance are rejected at inspection), every phase of a
periodic source drawn uniformly.  Modules, one topic each:

* :mod:`.quantities` -- the registry of varied quantities (data) and the
  ``[statistics]`` table of the spec;
* :mod:`.sampling` -- truncated distributions and counter-based random streams;
* :mod:`.metrics` -- the paper's totals and the ISO 230-2 figures per sample;
* :mod:`.statistics` -- percentiles, binomial yield intervals, sensitivity indices;
* :mod:`.engine` -- the block-wise run (shards, progress) and the summary;
* :mod:`.allocation` -- which tolerance to tighten for the most yield;
* :mod:`.report` -- the JSON and CSV documents.

No I/O, no typer, no rich.  scipy is imported lazily (inside functions).
"""

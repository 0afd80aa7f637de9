"""Running big studies in parts: worker processes (``--jobs``), parts of a run (``--shard``,
from a scheduler's job array with ``--shard auto``) and the manifests that let a re-run skip
the parts already done and let ``wormgear merge`` join them.

No typer, no rich; the environment is passed in (a mapping), never read here.
"""

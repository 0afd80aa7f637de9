"""The stage kinds, one module per kind (its keys, records, template values and toleranced keys:
:class:`~wormgear_cli.spec.kinds.base.StageKind`), and their registry :data:`KINDS`.

Adding a kind: its module here and one entry in :data:`KINDS`, its model in
``wormgear_cli/drive/<kind>.py`` and one entry in :data:`wormgear_cli.drive.models.MODELS`
(docs/development.md, "Extension points").
"""

from wormgear_cli.spec.kinds import belt, spur, worm
from wormgear_cli.spec.kinds.base import StageKind, Toleranced

#: kind name -> its record, in the order the docs list them
KINDS: dict[str, StageKind] = {k.name: k for k in (worm.KIND, spur.KIND, belt.KIND)}

__all__ = ["KINDS", "StageKind", "Toleranced"]

"""The two registries of stage kinds agree: every kind of the spec (spec.kinds.KINDS) has a model
(drive.models.MODELS) with the whole interface the train, the registry and the tolerance metrics
call, and every key a kind's record names is one of its own keys."""

from wormgear_cli.drive.models import MODELS
from wormgear_cli.spec.kinds import KINDS
from wormgear_cli.spec.stages import MEMBERS, STAGE_FIELDS

MODEL_INTERFACE = ("MEMBER_NAMES", "teeth", "mesh_orders", "base_circle", "tooth_deflection", "evaluate", "sources",
                   "compliance", "sampled_totals")


def test_every_spec_kind_has_a_model_with_the_whole_interface():
    assert list(MODELS) == list(KINDS)
    for kind, model in MODELS.items():
        missing = [name for name in MODEL_INTERFACE if not hasattr(model, name)]
        assert not missing, (kind, missing)
        assert len(model.MEMBER_NAMES) == 2, kind  # (input shaft's member, output shaft's member)


def test_a_kind_record_names_only_its_own_keys():
    for name, kind in KINDS.items():
        keys = {f.path for f in STAGE_FIELDS[name]}
        named = {*kind.ratio_keys, kind.load_key, *kind.examples, *(t.key for t in kind.toleranced),
                 *(p.key for p in kind.plausible), *kind.listed[0], *kind.listed[1]}
        assert named <= keys, (name, sorted(named - keys))
        assert tuple(kind.members) == MEMBERS[name]
        assert {f.path.split(".")[0] for f in STAGE_FIELDS[name] if "." in f.path} == set(kind.members), name


"""The spec layer: a drive file (TOML) read into validated, immutable records.

Units live in key names and are converted once, here.  Unknown keys are errors naming the
nearest valid key.  Modules: :mod:`~wormgear_cli.spec.loader` (the schema as data and its
validation), :mod:`~wormgear_cli.spec.toml` (TOML parsed within bounds),
:mod:`~wormgear_cli.spec.template` (the commented template of ``wormgear new``),
:mod:`~wormgear_cli.spec.kinds` (one module per stage kind: its keys, records, template values and
toleranced keys), :mod:`~wormgear_cli.spec.stages` (the ``[[stage]]`` tables, built from the kinds).
"""

from wormgear_cli.spec.loader import (
                                      FIELD_BY_PATH,
                                      FIELDS,
                                      UNIT_SCALE,
                                      Field,
                                      Spec,
                                      load_spec,
                                      loads_spec,
                                      raw_copy,
                                      spec_from_dict,
                                      value_origin,
                                      with_values,
)

__all__ = ["FIELD_BY_PATH", "FIELDS", "UNIT_SCALE", "Field", "Spec", "load_spec", "loads_spec", "raw_copy",
           "spec_from_dict", "value_origin", "with_values"]

"""Design files (TOML, docs/formats.md): load, validate, save.

Files speak millimetres, megapascals, tesla and kg/m^3 as their key names say; the
returned :class:`~design.records.Design` is in SI. Every bad value raises
:class:`DesignError` whose message names the key, what was expected and what was found.

The package, one concept per module: :mod:`~design.designfile.keys` (the keys, from the
registry, and reading one section), :mod:`~design.designfile.fields` (the external magnet
and the field sources), :mod:`~design.designfile.environment` (the obstacles),
:mod:`~design.designfile.checks` (checks of the whole design),
:mod:`~design.designfile.inputs` (reading an input file),
:mod:`~design.designfile.reader` (the document into a design) and
:mod:`~design.designfile.writer` (a design back to a file). The names below are
re-exported here.
"""

from __future__ import annotations

from design.designfile.checks import source_distance
from design.designfile.environment import OBSTACLE_KEYS
from design.designfile.inputs import MAX_INPUT_BYTES, read_input, read_regular
from design.designfile.keys import (
    EXTERNAL_SHAPES,
    OPTIONAL_KEYS,
    OPTIONAL_SECTIONS,
    SECTIONS,
    TOP_KEYS,
    UNIT_TOLERANCE,
    DesignError,
    Key,
)
from design.designfile.reader import (
    default_design,
    design_from_dict,
    load_design,
    loads_design,
    revalidated,
)
from design.designfile.writer import design_to_dict, dumps_design, save_design

__all__ = [
    "EXTERNAL_SHAPES",
    "MAX_INPUT_BYTES",
    "OBSTACLE_KEYS",
    "OPTIONAL_KEYS",
    "OPTIONAL_SECTIONS",
    "SECTIONS",
    "TOP_KEYS",
    "UNIT_TOLERANCE",
    "DesignError",
    "Key",
    "default_design",
    "design_from_dict",
    "design_to_dict",
    "dumps_design",
    "load_design",
    "loads_design",
    "read_input",
    "read_regular",
    "revalidated",
    "save_design",
    "source_distance",
]

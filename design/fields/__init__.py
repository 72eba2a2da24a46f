"""Field kernels (one per file, as magpylib's): each gives the flux density B and its
gradient G = dB/dp of one source on CasADi symbols, so the same physics serves numbers,
compiled batches and the NLPs' exact derivatives; :mod:`design.fields.sources` composes
them into the field of a design's sources.

- :mod:`~design.fields.uniform`: a uniform field (no gradient);
- :mod:`~design.fields.cylinder`: the axially magnetised cylinder (exact, closed-form
  gradient, :mod:`design.cylinder_field`);
- :mod:`~design.fields.cuboid`: the uniformly magnetised cuboid (exact);
- :mod:`~design.fields.sphere`: the uniformly magnetised sphere (exact);
- :mod:`~design.fields.coil`: a circular current loop (exact, elliptic integrals);
- :mod:`~design.fields.fieldmap`: a field sampled on a grid, cubic splines.

SI units are used for all inputs and outputs.
"""

from design.fields.coil import coil_field, coil_field_function, coil_flux_density
from design.fields.cuboid import cuboid_field, cuboid_field_function, cuboid_flux_density
from design.fields.cylinder import cylinder_field
from design.fields.fieldmap import FieldMap, FieldMapError, map_field, read_field_map
from design.fields.sources import KINDS, PERMANENT, source_field, superposed_field
from design.fields.sphere import sphere_field, sphere_field_function
from design.fields.uniform import uniform_field

__all__ = [
    "KINDS",
    "PERMANENT",
    "FieldMap",
    "FieldMapError",
    "coil_field",
    "coil_field_function",
    "coil_flux_density",
    "cuboid_field",
    "cuboid_field_function",
    "cuboid_flux_density",
    "cylinder_field",
    "map_field",
    "read_field_map",
    "source_field",
    "sphere_field",
    "sphere_field_function",
    "superposed_field",
    "uniform_field",
]

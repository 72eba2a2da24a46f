"""Materials on offer for the transmissions (catheter tube and inner wire).

Each entry gives what the design NLP needs: Young's modulus, Poisson's ratio and density
(which the model takes as design parameters) and the allowable bending strain (the
largest surface strain in bending the material takes elastically and repeatably, used
as the strain constraint). Values are typical room-temperature data sheet values; a
study can override a tube's allowable strain (``constraints.catheter_max_strain``,
``constraints.wire_max_strain``). SI units are used for all fields.

Sources (one per material, also in each entry's ``source``):

- NiTi (superelastic, austenitic at body/room temperature): Fort Wayne Metals, *Nitinol*
  data sheet (austenite modulus 41-75 GPa, density 6.45 g/cm^3); Duerig, Pelton &
  Stoeckel, "An overview of nitinol medical applications", Mater. Sci. Eng. A 273-275
  (1999) 149-160 (recoverable strain about 6-8 %; 6 % used). E = 60 GPa is the value the
  paper's demonstrator uses, inside the data sheet range.
- Stainless steel 304V spring-temper wire: Fort Wayne Metals, *304V* data sheet (E = 193
  GPa, yield about 1.6-2.0 GPa, so yield strain about 0.8-1 %; 0.8 % used).
- PTFE: DuPont / Chemours, *Teflon PTFE properties handbook* (tensile modulus about 0.4-0.6
  GPa, Poisson 0.46, density 2.2 g/cm^3); elastic strain a few percent (3 % used, the
  issue's "PTFE a few %"; PTFE creeps, so keep it modest).
- Pebax 7233 (72D) and Pebax 6333 (63D): Arkema, *Pebax* technical data sheets (flexural
  modulus 513 and 285 MPa, density 1.01 g/cm^3); thermoplastic elastomers with yield
  strains near 20 %; 5 % used as a conservative repeatable bending strain.
- Nylon 12 (e.g. Vestamid L2140, Grilamid L25): Evonik / EMS data sheets (tensile modulus
  about 1.1-1.4 GPa, yield strain about 5 %; 4 % used), Poisson about 0.40.
- Polyimide (Kapton HN type tubing): DuPont, *Kapton HN* data sheet (tensile modulus 2.5
  GPa, density 1.42 g/cm^3, "yield point at 3 %"; 3 % used), Poisson 0.34.
- PEEK (Victrex 450G): Victrex data sheet (tensile modulus 3.7 GPa, yield strain 5 %; 4 %
  used, density 1.30 g/cm^3), Poisson 0.40.
"""

from __future__ import annotations

from dataclasses import dataclass

from design.suggest import did_you_mean
from design.units import MPA

GPA = 1e3 * MPA


@dataclass(frozen=True)
class Material:
    """One transmission material.

    name : key in :data:`MATERIALS`.
    youngs_modulus : Young's modulus. [Pa]
    poisson_ratio : Poisson's ratio. [-]
    density : mass density. [kg/m^3]
    allowable_strain : largest elastic bending strain allowed at the surface. [-]
    source : where the numbers come from.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float
    density: float
    allowable_strain: float
    source: str


_FWM = "Fort Wayne Metals data sheet"
MATERIALS: dict[str, Material] = {
    m.name: m
    for m in (
        Material(
            "niti",
            60 * GPA,
            0.33,
            6450.0,
            0.06,
            f"{_FWM} (Nitinol); Duerig, Pelton & Stoeckel, Mater. Sci. Eng. A 273 (1999)",
        ),
        Material("steel_304v", 193 * GPA, 0.29, 8000.0, 0.008, f"{_FWM} (304V spring temper)"),
        Material("ptfe", 550 * MPA, 0.46, 2200.0, 0.03, "Chemours Teflon PTFE handbook"),
        Material("pebax_7233", 513 * MPA, 0.45, 1010.0, 0.05, "Arkema Pebax 7233 data sheet"),
        Material("pebax_6333", 285 * MPA, 0.45, 1010.0, 0.05, "Arkema Pebax 6333 data sheet"),
        Material("nylon_12", 1200 * MPA, 0.40, 1010.0, 0.04, "Evonik Vestamid L2140 data sheet"),
        Material("polyimide", 2500 * MPA, 0.34, 1420.0, 0.03, "DuPont Kapton HN data sheet"),
        Material("peek", 3700 * MPA, 0.40, 1300.0, 0.04, "Victrex 450G data sheet"),
    )
}
"""Materials by name."""


def material(name: str) -> Material:
    """The material called ``name``; KeyError names the valid ones (and the closest)."""
    try:
        return MATERIALS[name]
    except KeyError:
        hint = did_you_mean(name, MATERIALS, cutoff=0.5)
        raise KeyError(
            f"unknown material {name!r}; expected one of {', '.join(MATERIALS)}{hint}"
        ) from None

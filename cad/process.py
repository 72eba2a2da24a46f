"""Print processes: fits, clearances, smallest printable wall and build volume.

CAD works in millimetres: every length here is in mm. The values are design rules for a
typical machine of each kind (stated per field), not properties of a particular printer;
pass your own :class:`PrintProcess` to :func:`cad.build.build_parts` to use others.
"""

from __future__ import annotations

from dataclasses import dataclass

from cad.errors import CadError
from design.mounting import WALL_FACTOR
from design.units import MM


def mm(length_m: float) -> float:
    """Convert a length (or an array of them) from the design's SI metres to CAD
    millimetres. [mm]"""
    return length_m * (1 / MM)  # 1 / MM is exactly 1000.0: x * 1000, rounded once


@dataclass(frozen=True)
class PrintProcess:
    """How parts are made, as far as the geometry must know.

    name : ``"fdm"`` or ``"resin"`` (or your own).
    printer : The machine whose build volume is used, for the report.
    min_wall_mm : Thinnest wall the process prints reliably. [mm]
    fit_allowance_mm : Added to the diameter of a seat for a bought part that is glued or
        pushed in (magnet ring, catheter, wire, bushing). [mm]
    running_clearance_mm : Diametral clearance between parts that turn on each other. [mm]
    backlash_mm : Circular backlash of a gear mesh, at the pitch circle. [mm]
    build_volume_mm : Usable build volume x, y, z. [mm]
    material : The printed material, for the parts list.
    material_density_kg_m3 : Density of the printed material, for part masses. [kg/m^3]
    linear_deflection_mm : Chord tolerance of the exported meshes. [mm]
    angular_deflection_rad : Angular tolerance of the exported meshes. [rad]
    """

    name: str
    printer: str
    min_wall_mm: float
    fit_allowance_mm: float
    running_clearance_mm: float
    backlash_mm: float
    build_volume_mm: tuple[float, float, float]
    material: str
    material_density_kg_m3: float
    linear_deflection_mm: float = 0.02
    angular_deflection_rad: float = 0.3

    @property
    def wall_mm(self) -> float:
        """Default structural wall: 25 % above the process minimum
        (:data:`design.mounting.WALL_FACTOR`). [mm]"""
        return WALL_FACTOR * self.min_wall_mm


# FDM: 0.4 mm nozzle, two perimeters make the thinnest reliable wall (0.8 mm); Prusa MK4
# build volume 250 x 210 x 220 mm.
FDM = PrintProcess(
    name="fdm",
    printer="Prusa MK4 class (250 x 210 x 220 mm)",
    min_wall_mm=0.8,
    fit_allowance_mm=0.15,
    running_clearance_mm=0.3,
    backlash_mm=0.2,
    build_volume_mm=(250.0, 210.0, 220.0),
    material="PLA",
    material_density_kg_m3=1240.0,
)

# Resin (SLA/MSLA): supported walls down to about 0.4 mm; Formlabs Form 3+ build volume
# 145 x 145 x 185 mm.
RESIN = PrintProcess(
    name="resin",
    printer="Formlabs Form 3+ class (145 x 145 x 185 mm)",
    min_wall_mm=0.4,
    fit_allowance_mm=0.05,
    running_clearance_mm=0.1,
    backlash_mm=0.1,
    build_volume_mm=(145.0, 145.0, 185.0),
    material="photopolymer",
    material_density_kg_m3=1180.0,  # typical standard resin
)

PROCESSES: dict[str, PrintProcess] = {p.name: p for p in (FDM, RESIN)}


def get_process(process: str | PrintProcess) -> PrintProcess:
    """Return the :class:`PrintProcess` named ``process`` (``"fdm"`` or ``"resin"``)."""
    if isinstance(process, PrintProcess):
        return process
    try:
        return PROCESSES[process]
    except KeyError:
        names = ", ".join(repr(n) for n in PROCESSES)
        raise CadError(f"process must be one of {names}; got {process!r}") from None

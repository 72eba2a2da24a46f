"""Print processes: the one table of fits, clearances, thinnest walls and build volumes.

Both the model (the printed tip's size and mass, :mod:`design.mounting`) and the CAD
(:mod:`cad.process`, its millimetre view) read this table; neither keeps numbers of its
own. SI units throughout. The values are design rules for a typical machine of each kind
(stated per entry), not properties of a particular printer: a design file's
``[tip.mounting]`` keys override the tip pieces' numbers, and ``cad`` takes a
:class:`PrintProcess` of your own for the other parts.
"""

from __future__ import annotations

from dataclasses import dataclass

from design.units import MM


@dataclass(frozen=True)
class PrintProcess:
    """How parts are made, as far as their geometry must know. [SI]

    name : ``"resin"`` or ``"fdm"`` (or your own).
    printer : The machine class whose build volume is used, for reports.
    material : The printed material, for the parts list.
    min_wall : Thinnest wall the process prints reliably. [m]
    fit_allowance : Added to the diameter of a seat for a bought part that is glued or
        pushed in (ring, catheter, wire, bushing). [m]
    running_clearance : Diametral (and axial) clearance between parts that turn on each
        other. [m]
    backlash : Circular backlash of a gear mesh, at the pitch circle. [m]
    build_volume : Usable build volume x, y, z. [m]
    density : Density of the printed material. [kg/m^3]
    hole_shrink : How much smaller than drawn a small vertical hole prints (diametral):
        what :mod:`cad` adds to the drawn diameter of a bore that must fit, where the
        design asks for hole compensation. [m]
    linear_deflection : Chord tolerance of the exported meshes. [m]
    angular_deflection : Angular tolerance of the exported meshes. [rad]
    """

    name: str
    printer: str
    material: str
    min_wall: float
    fit_allowance: float
    running_clearance: float
    backlash: float
    build_volume: tuple[float, float, float]
    density: float
    hole_shrink: float = 0.0
    linear_deflection: float = 0.02 * MM
    angular_deflection: float = 0.3

    @property
    def wall(self) -> float:
        """The structural wall: :data:`WALL_FACTOR` times the process minimum. [m]"""
        return WALL_FACTOR * self.min_wall


WALL_FACTOR = 1.25
"""Structural wall over the process's thinnest reliable wall: a quarter's margin. [-]"""

RESIN = PrintProcess(
    name="resin",
    printer="Formlabs Form 3+ class (145 x 145 x 185 mm)",
    material="photopolymer",
    # supported walls down to about 0.4 mm; glued fits 0.05 mm over size, running 0.1 mm
    min_wall=0.4 * MM,
    fit_allowance=0.05 * MM,
    running_clearance=0.1 * MM,
    backlash=0.1 * MM,
    build_volume=(145 * MM, 145 * MM, 185 * MM),
    density=1180.0,  # typical standard resin
    # small holes close by about 0.05 mm (overcure at the bore's wall)
    hole_shrink=0.05 * MM,
)
FDM = PrintProcess(
    name="fdm",
    printer="Prusa MK4 class (250 x 210 x 220 mm)",
    material="PLA",
    # 0.4 mm nozzle: two perimeters make the thinnest reliable wall, 0.8 mm
    min_wall=0.8 * MM,
    fit_allowance=0.15 * MM,
    running_clearance=0.3 * MM,
    backlash=0.2 * MM,
    build_volume=(250 * MM, 210 * MM, 220 * MM),
    density=1240.0,
    # a vertical hole's polygon and the squeezed first perimeter: about 0.2 mm undersize
    hole_shrink=0.2 * MM,
)
PROCESSES: dict[str, PrintProcess] = {p.name: p for p in (RESIN, FDM)}
"""The print processes by name; the tip pieces default to resin (the finest)."""
DEFAULT_PROCESS = "resin"

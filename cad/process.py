"""The print processes in millimetres: the CAD's view of :mod:`design.process`.

CAD works in millimetres: every length here is in mm. The numbers are the design's one
process table (:data:`design.process.PROCESSES`, SI), which the model reads too; this
module only converts them. Pass a :class:`design.process.PrintProcess` of your own to
:func:`cad.build.build_parts` to use other rules.
"""

from __future__ import annotations

from dataclasses import dataclass

from cad.errors import CadError
from design.process import PROCESSES as SI_PROCESSES
from design.process import PrintProcess
from design.units import MM


def mm(length_m: float) -> float:
    """Convert a length (or an array of them) from the design's SI metres to CAD
    millimetres. [mm]"""
    return length_m * (1 / MM)  # 1 / MM is exactly 1000.0: x * 1000, rounded once


@dataclass(frozen=True)
class CadProcess:
    """A :class:`design.process.PrintProcess` in the CAD's units (mm).

    si : The process as the design knows it. [SI]
    """

    si: PrintProcess

    @property
    def name(self) -> str:
        """``"fdm"``, ``"resin"`` or your own."""
        return self.si.name

    @property
    def printer(self) -> str:
        """The machine class whose build volume is used."""
        return self.si.printer

    @property
    def material(self) -> str:
        """The printed material."""
        return self.si.material

    @property
    def min_wall_mm(self) -> float:
        """Thinnest wall the process prints reliably. [mm]"""
        return mm(self.si.min_wall)

    @property
    def wall_mm(self) -> float:
        """Default structural wall (:data:`design.process.WALL_FACTOR` x the minimum). [mm]"""
        return mm(self.si.wall)

    @property
    def fit_allowance_mm(self) -> float:
        """Diametral allowance of a seat for a glued or pushed-in part. [mm]"""
        return mm(self.si.fit_allowance)

    @property
    def running_clearance_mm(self) -> float:
        """Diametral clearance between parts that turn on each other. [mm]"""
        return mm(self.si.running_clearance)

    @property
    def backlash_mm(self) -> float:
        """Circular backlash of a gear mesh at the pitch circle. [mm]"""
        return mm(self.si.backlash)

    @property
    def build_volume_mm(self) -> tuple[float, float, float]:
        """Usable build volume x, y, z. [mm]"""
        x, y, z = self.si.build_volume
        return mm(x), mm(y), mm(z)

    @property
    def hole_shrink_mm(self) -> float:
        """How much smaller than drawn a small vertical hole prints (diametral). [mm]"""
        return mm(self.si.hole_shrink)

    @property
    def material_density_kg_m3(self) -> float:
        """Density of the printed material. [kg/m^3]"""
        return self.si.density

    @property
    def linear_deflection_mm(self) -> float:
        """Chord tolerance of the exported meshes. [mm]"""
        return mm(self.si.linear_deflection)

    @property
    def angular_deflection_rad(self) -> float:
        """Angular tolerance of the exported meshes. [rad]"""
        return self.si.angular_deflection


PROCESSES: dict[str, CadProcess] = {n: CadProcess(p) for n, p in sorted(SI_PROCESSES.items())}
"""The design's processes (:data:`design.process.PROCESSES`) in mm, by name (sorted)."""
FDM, RESIN = PROCESSES["fdm"], PROCESSES["resin"]


def get_process(process: str | PrintProcess | CadProcess) -> CadProcess:
    """The :class:`CadProcess` of ``process``: a name (``"fdm"`` or ``"resin"``), a
    :class:`design.process.PrintProcess` or a :class:`CadProcess`."""
    if isinstance(process, CadProcess):
        return process
    if isinstance(process, PrintProcess):
        return CadProcess(process)
    try:
        return PROCESSES[process]
    except KeyError:
        names = ", ".join(repr(n) for n in PROCESSES)
        raise CadError(f"process must be one of {names}; got {process!r}") from None

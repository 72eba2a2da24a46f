"""One entry point: build, export, check and render every part of a design.

``build_parts(design, out_dir, process="fdm")`` writes, into ``out_dir`` (all in mm):

    ringpair_robot.step        STEP assembly, one named node per part instance
    stl/<part>.stl             one STL per printed part, in its print orientation
    plate_<process>_<k>.3mf    print plate(s) with every copy of every printed part
    checks.csv                 the printability and fit table (cad.checks)
    parts.csv                  parts list: quantity, material, volume, mass, size, file
    bom.csv                    bill of materials: what to buy (magnets, tube and wire with
                               cut lengths, screws, adhesive) and what to print (cad.bom)
    cad_summary.json           tracking groove, self-locking and gear numbers, timings
    renders/...png             each part, assembly, actuator, exploded, tip, setup (the robot
                               and its field sources)

and returns a :class:`CadReport` with the same numbers.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from cad.actuator import build_actuator
from cad.assembly import RobotAssembly, build_assembly
from cad.bom import bill_of_materials, bom_totals, write_bom_csv
from cad.checks import (
    CheckRow,
    gear_checks,
    interference_checks,
    part_checks,
    place_meshes,
    rows_as_dicts,
    write_csv,
)
from cad.export import PartMesh, arrange_plates, export_3mf, export_step, export_stl
from cad.layout import ActuatorSpec
from cad.meshing import tessellate
from cad.mounting import MountingSpec, TrackingReport, build_mounting_pieces
from cad.process import CadProcess, get_process, mm
from cad.render import render_all
from cad.selflocking import SelfLocking
from cad.stock import fasteners
from design.atomic import write_text
from design.process import PrintProcess
from design.records import Design
from design.strict_json import dumps_strict
from design.units import GRAM, MM3

TIP_PIECES = ("mounting_piece_proximal", "mounting_piece_distal")
"""The printed parts the model carries (:mod:`design.mounting`)."""

STEP_FILE = "ringpair_robot.step"


@dataclass
class CadReport:
    """What :func:`build_parts` made and found.

    out_dir : Where the files are.
    process : Name of the print process.
    files : Every file written.
    checks : The check table, one dict per row (``item, check, value, limit, unit, passed,
        note``).
    parts : Parts list, one dict per part (``name, quantity, printed, material,
        volume_mm3, mass_g, size_mm, file, description``).
    tracking : Groove pitch, travel, resolution [deg/mm] and range [deg] per piece.
    self_locking : The worm drives' self-locking numbers.
    drive : Gear numbers (module, teeth, ratio, lead angle, centre distance, ...).
    timings_s : Seconds per stage (build, export, check, render, total).
    assembly : The solids themselves (mm), for callers that go on working with them.
    bom : The bill of materials, one dict per row (:data:`cad.bom.BOM_COLUMNS`).
    tip : The printed tip: process, material, outer diameter and rigid length [mm], mass
        of both pieces [g], wall [mm].
    """

    out_dir: Path
    process: str
    files: list[Path] = field(default_factory=list)
    checks: list[dict[str, object]] = field(default_factory=list)
    parts: list[dict[str, object]] = field(default_factory=list)
    tracking: tuple[TrackingReport, ...] = ()
    self_locking: SelfLocking | None = None
    drive: dict[str, float] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)
    assembly: RobotAssembly | None = None
    bom: list[dict[str, object]] = field(default_factory=list)
    tip: dict[str, object] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """True when every check passed."""
        return all(bool(r["passed"]) for r in self.checks)

    @property
    def failures(self) -> list[dict[str, object]]:
        """The rows that did not pass."""
        return [r for r in self.checks if not r["passed"]]

    def summary(self) -> str:
        """A few lines for the terminal."""
        prox = self.tracking[0] if self.tracking else None
        lines = [
            f"CAD ({self.process}, mm): {len(self.files)} files in {self.out_dir}",
            f"checks: {sum(bool(r['passed']) for r in self.checks)}/{len(self.checks)} passed",
        ]
        if prox is not None:
            lines.append(
                f"tracking groove: {prox.resolution_deg_per_mm:.2f} deg per mm of notch travel, "
                f"range {prox.range_deg:.1f} deg over {prox.travel_mm:g} mm (pitch "
                f"{prox.pitch_mm:.2f} mm)"
            )
        if self.self_locking is not None:
            lines.append(f"worm drives: {self.self_locking.summary()}")
        lines.append("time: " + ", ".join(f"{k} {v:.1f} s" for k, v in self.timings_s.items()))
        for r in self.failures:
            lines.append(
                f"FAILED {r['item']} {r['check']}: {r['value']:.4g} {r['unit']} ({r['note']})"
            )
        return "\n".join(lines)

    def to_json(self) -> dict[str, object]:
        """The report's numbers as plain JSON types (no check rows, no file list)."""
        return {
            "process": self.process,
            "unit": "mm",
            "tracking": [asdict(t) for t in self.tracking],
            "self_locking": None
            if self.self_locking is None
            else {**asdict(self.self_locking), "self_locking": self.self_locking.self_locking},
            "drive": self.drive,
            "timings_s": self.timings_s,
            "passed": self.passed,
            "parts": self.parts,
            "bom": self.bom,
            "tip": self.tip,
            "bom_totals": bom_totals(self.bom) if self.bom else None,
        }


def part_meshes(assembly: RobotAssembly, process: CadProcess) -> dict[str, PartMesh]:
    """Tessellate every part once, at the process's export tolerance (print frame). [mm]"""
    out = {}
    for name, part in assembly.parts.items():
        v, t = tessellate(part.solid, process.linear_deflection_mm, process.angular_deflection_rad)
        out[name] = PartMesh(name, v, t, part.quantity)
    return out


PARTS_COLUMNS = (
    "part",
    "quantity",
    "printed",
    "material",
    "volume_mm3",
    "mass_g",
    "size_x_mm",
    "size_y_mm",
    "size_z_mm",
    "file",
    "description",
)
"""Columns of ``parts.csv``: one row per distinct part; volume and mass of one piece;
size = bounding box in the part's print frame (bought parts: their own frame); file =
where its geometry is, relative to the CAD folder."""


def _bought_materials(design: Design) -> dict[str, tuple[str, float]]:
    """Bought part -> (material, density [kg/m^3]) from the design file."""
    return {
        "ring_magnet": (f"magnet, remanence {design.tip.magnet_remanence:g} T", design.tip.density),
        "catheter": ("catheter tube", design.robot.catheter.density),
        "wire": ("wire", design.robot.wire.density),
    }


def _parts_table(
    assembly: RobotAssembly,
    process_of: Callable[[str], CadProcess],
    design: Design,
    meshes: dict[str, PartMesh],
) -> list[dict[str, object]]:
    """One dict per part: name, quantity, printed, material, volume_mm3 [mm^3], mass_g [g]
    (one piece, 4 significant digits; printed parts at the process material's density,
    bought ones at the design's, screws nominal), size_mm (bounding box x, y, z of its
    exported mesh: OCC's box of a curved solid can be loose by tenths of a mm) [mm], file,
    description."""
    bought = _bought_materials(design)
    rows = []
    for name, part in assembly.parts.items():
        size = np.ptp(np.asarray(meshes[name].vertices), axis=0)
        volume = part.solid.Volume()
        process = process_of(name)
        printed = (f"{process.material}, {process.name} print", process.material_density_kg_m3)
        material, density = printed if part.printed else bought[name]
        rows.append(
            {
                "name": name,
                "quantity": part.quantity,
                "printed": part.printed,
                "process": process.name if part.printed else "",
                "material": material,
                "volume_mm3": round(volume, 3),
                "mass_g": float(f"{volume * MM3 * density / GRAM:.4g}"),
                "size_mm": [round(float(s), 3) for s in size],
                "file": f"stl/{name}.stl" if part.printed else STEP_FILE,
                "description": part.description,
            }
        )
    for f in fasteners(assembly.actuator.layout):
        head = max(f.head, f.diameter)
        # nominal: the thread's shank and a head as tall as the thread is wide (ISO 4762)
        volume = math.pi / 4 * (f.diameter**2 * f.length + f.head**2 * f.diameter)
        rows.append(
            {
                "name": f.name,
                "quantity": f.quantity,
                "printed": False,
                "material": f"steel, {f.standard}",
                "volume_mm3": round(volume, 3),
                "mass_g": float(f"{volume * MM3 * STEEL_DENSITY / GRAM:.4g}"),
                "size_mm": [head, head, f.length + (f.diameter if f.head else 0.0)],
                "file": "bought",
                "description": f.where,
            }
        )
    return rows


STEEL_DENSITY = 7850.0
"""Density of the screws' steel, for their nominal mass. [kg/m^3]"""


def _write_parts_csv(rows: list[dict[str, object]], path: Path) -> Path:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=PARTS_COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        x, y, z = r["size_mm"]  # type: ignore[misc]
        w.writerow(
            {c: r[c] for c in PARTS_COLUMNS if c in r}
            | {"part": r["name"], "size_x_mm": x, "size_y_mm": y, "size_z_mm": z}
        )
    write_text(path, buf.getvalue())
    return path


def build_parts(
    design: Design,
    out_dir: str | Path,
    process: str | PrintProcess = "fdm",
    *,
    mounting: MountingSpec | None = None,
    actuator: ActuatorSpec | None = None,
    material_pair: str | None = None,
    render: bool = True,
    tip_process: str | PrintProcess | None = None,
) -> CadReport:
    """Build, export, check and render every part of ``design``.

    Parameters
    ----------
    design : The robot (SI, as loaded from a design file).
    out_dir : Output directory (created); files in it are replaced atomically.
    process : ``"fdm"`` or ``"resin"``, or a :class:`~cad.process.PrintProcess`.
    tip_process : the process of the two tip pieces (the parts the model carries, whose
        fits and walls set their size and mass); None: the design's own ``tip.mounting``
        (process, wall, fits, density: the pieces the model knows); another process
        reprints them with its numbers (:func:`cad.mounting.tip_design`).
    mounting, actuator : Designer's choices for the tip pieces and the actuator.
    material_pair : Worm/wheel material pair for the self-locking check.
    render : Also write the PNG renders.

    Raises
    ------
    CadError
        (a ValueError, :class:`~cad.errors.CadError`) for impossible dimensions.
    """
    proc = get_process(process)
    out = Path(out_dir)
    report = CadReport(out_dir=out, process=proc.name)
    t0 = time.perf_counter()

    # All geometry first: impossible dimensions fail here, before anything is written.
    pieces = build_mounting_pieces(design, tip_process, mounting)
    tip = pieces.process
    act = build_actuator(design, proc, actuator, material_pair)
    assembly = build_assembly(design, act, pieces)
    out.mkdir(parents=True, exist_ok=True)
    t1 = time.perf_counter()

    meshes = part_meshes(assembly, proc)
    printed = [m for n, m in meshes.items() if assembly.parts[n].printed]
    stl_paths = {m.name: export_stl(m, out / "stl" / f"{m.name}.stl") for m in printed}
    report.files += list(stl_paths.values())
    report.files.append(export_step(assembly, out / STEP_FILE))

    def process_of(name: str) -> CadProcess:
        return tip if name in TIP_PIECES else proc

    for each in {p.name: p for p in (proc, tip)}.values():  # one set of plates per printer
        mine = [m for m in printed if process_of(m.name).name == each.name]
        for k, plate in enumerate(arrange_plates(mine, each), start=1):
            path = out / f"plate_{each.name}_{k}.3mf"
            report.files.append(export_3mf(meshes, plate, path, each))
    t2 = time.perf_counter()

    rows: list[CheckRow] = []
    read_back = {}
    for name, path in stl_paths.items():
        part_rows, mesh = part_checks(
            name, path, assembly.parts[name].solid.Volume(), process_of(name), act.teeth.get(name)
        )
        rows += part_rows
        read_back[name] = mesh
    for name, m in meshes.items():
        if name not in read_back:
            read_back[name] = trimesh.Trimesh(m.vertices, m.triangles, process=True)
    placed = place_meshes(assembly, read_back)
    interference = interference_checks(placed)
    rows += interference
    rows += gear_checks(assembly, interference)
    report.checks = rows_as_dicts(rows)
    report.files.append(write_csv(rows, out / "checks.csv"))
    report.parts = _parts_table(assembly, process_of, design, meshes)
    report.files.append(_write_parts_csv(report.parts, out / "parts.csv"))
    report.bom = bill_of_materials(design, assembly, report.parts)
    report.files.append(write_bom_csv(report.bom, out / "bom.csv"))
    t3 = time.perf_counter()

    if render:
        render_meshes = {
            n: (np.asarray(m.vertices), np.asarray(m.faces)) for n, m in read_back.items()
        }
        report.files += render_all(assembly, out / "renders", render_meshes, design)
    t4 = time.perf_counter()

    report.assembly = assembly
    g = pieces.geometry
    report.tip = {
        "process": tip.name,
        "material": tip.material,
        "outer_diameter_mm": round(pieces.dims.outer_diameter, 3),
        "rigid_length_mm": round(mm(g.rigid_length), 3),
        "mass_g": float(f"{(g.proximal_mass + g.distal_mass) / GRAM:.3g}"),
        "wall_mm": pieces.dims.wall,
    }
    report.tracking = pieces.tracking()
    report.self_locking = act.locking
    report.drive = act.layout.drive.table()
    report.timings_s = {
        "build": t1 - t0,
        "export": t2 - t1,
        "check": t3 - t2,
        "render": t4 - t3,
        "total": t4 - t0,
    }
    summary = out / "cad_summary.json"
    write_text(summary, dumps_strict(report.to_json()))
    report.files.append(summary)
    return report

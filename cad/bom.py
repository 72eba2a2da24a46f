"""The bill of materials: what to buy and what to print for one robot (``cad/bom.csv``).

CAD works in millimetres: sizes in mm, masses in g. One row per item:

- bought: the two ring magnets (NdFeB grade from the design's remanence, diametrically
  magnetised, their sizes as the design file rounds them), every field source with a body
  (:func:`field_rows`: each magnet's grade, size, pose and north; a coil's turns, current
  and pose), the catheter tube and the wire with their cut
  lengths (:mod:`cad.stock`), every screw (:func:`cad.stock.fasteners`) and the adhesive;
- provided: a uniform field or a field map, nothing to buy (said so);
- printed: every printed part with its process, material, mass, the face on the bed and
  its supports (:mod:`cad.printing`).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from cad.assembly import RobotAssembly
from cad.printing import print_setup
from cad.process import mm
from cad.stock import cuts, fasteners
from design.atomic import write_text
from design.records import Design

BOM_COLUMNS = (
    "item",
    "kind",
    "quantity",
    "specification",
    "size_mm",
    "cut_length_mm",
    "process",
    "material",
    "mass_g",
    "on_bed",
    "supports",
    "note",
)
"""Columns of ``bom.csv``; ``kind`` is ``bought`` or ``printed``; ``mass_g`` is of one
piece; ``cut_length_mm`` only for tube and wire stock."""

NDFEB_GRADES: dict[str, float] = {
    "N35": 1.19,
    "N38": 1.24,
    "N40": 1.27,
    "N42": 1.31,
    "N45": 1.35,
    "N48": 1.39,
    "N50": 1.42,
    "N52": 1.45,
    "N55": 1.49,
}
"""Sintered NdFeB grades and their typical remanence (middle of the grade's range). [T]"""
GRADE_TOLERANCE = 0.03
"""Largest difference between a design's remanence and the grade named for it. [T]"""
NDFEB_DENSITY = 7500.0
"""Density of sintered NdFeB, for the external magnet's mass. [kg/m^3]"""
TRIM_ALLOWANCE_MM = 20.0
"""Stock bought beyond a cut length, for trimming both ends. [mm]"""


def magnet_grade(remanence: float) -> str:
    """The NdFeB grade whose typical remanence is nearest ``remanence`` [T], or a note that
    none lies within :data:`GRADE_TOLERANCE`."""
    grade, br = min(NDFEB_GRADES.items(), key=lambda kv: abs(kv[1] - remanence))
    if abs(br - remanence) <= GRADE_TOLERANCE:
        return f"NdFeB {grade} (remanence {remanence:.2f} T)"
    return f"remanence {remanence:.2f} T (no NdFeB grade within {GRADE_TOLERANCE:g} T)"


def _size(*values: float) -> str:
    return " x ".join(f"{v:.2f}".rstrip("0").rstrip(".") for v in values)


def _modulus(e: float) -> str:
    """A Young's modulus in MPa below 1 GPa, else in GPa. [Pa]"""
    return f"{e / 1e9:.3g} GPa" if e >= 1e9 else f"{e / 1e6:.3g} MPa"


def _direction(v: Any) -> str:
    return "[" + ", ".join(f"{float(x):.3g}" for x in np.asarray(v, dtype=float)) + "]"


def _blank() -> dict[str, Any]:
    return {k: "" for k in BOM_COLUMNS} | {"quantity": 1, "cut_length_mm": None, "mass_g": None}


def _magnet_mass(volume: float) -> float:
    """Mass of a sintered NdFeB magnet of ``volume`` [m^3], 4 significant digits. [g]"""
    return float(f"{volume * NDFEB_DENSITY * 1e3:.4g}")


def field_rows(design: Design) -> list[dict[str, Any]]:
    """One row per field source of ``design``: the ``[external_magnet]``, then each of
    ``[[field.sources]]`` (``source_<n>``, numbered from 1 as in the file). Permanent
    magnets and coils are ``bought`` (a coil wound or bought to its turns, radius and
    current); a uniform field and a field map are ``provided`` (the scanner's, the coil
    system's, whatever the map was measured of): nothing to buy, said so. [mm, g]"""
    out: list[dict[str, Any]] = []

    def row(item: str, kind: str, spec: str, size: str, mass: float | None, note: str,
            material: str = "") -> None:  # fmt: skip
        out.append({"item": item, "kind": kind, "specification": spec, "size_mm": size,
                    "mass_g": mass, "note": note, "material": material})  # fmt: skip

    ext = design.external_magnet
    if ext is not None:
        row(
            "external_magnet", "bought",
            f"cylinder magnet, {magnet_grade(ext.remanence)}, magnetised axially",
            f"diameter {_size(mm(ext.diameter))}, length {_size(mm(ext.length))}",
            _magnet_mass(np.pi / 4 * ext.diameter**2 * ext.length),
            f"centre at {_direction(np.asarray(ext.center) * 1e3)} mm, north along "
            f"{_direction(ext.magnetization)} (base frame)",
            "sintered NdFeB",
        )  # fmt: skip
    for n, s in enumerate(design.sources, start=1):
        item, centre = f"source_{n}", f"{_direction(np.asarray(s.center) * 1e3)} mm"
        at = f"centre at {centre}"
        north = f"{at}, north along {_direction(s.magnetization)} (base frame)"
        grade = magnet_grade(s.remanence)
        if s.kind == "cylinder":
            row(item, "bought", f"cylinder magnet, {grade}, magnetised axially",
                f"diameter {_size(mm(s.diameter))}, length {_size(mm(s.length))}",
                _magnet_mass(np.pi / 4 * s.diameter**2 * s.length), north,
                "sintered NdFeB")  # fmt: skip
        elif s.kind == "cuboid":
            a, b, c = s.dimensions
            row(item, "bought", f"block magnet, {grade}",
                f"{_size(mm(a), mm(b), mm(c))} (along x, y, z)", _magnet_mass(a * b * c),
                north, "sintered NdFeB")  # fmt: skip
        elif s.kind == "sphere":
            row(item, "bought", f"sphere magnet, {grade}", f"diameter {_size(mm(s.diameter))}",
                _magnet_mass(np.pi / 6 * s.diameter**3), north, "sintered NdFeB")  # fmt: skip
        elif s.kind == "coil":
            row(item, "bought",
                f"coil, {s.turns:g} turns of {s.current:.3g} A ({s.turns * s.current:.4g} "
                "ampere-turns), wound or bought to these numbers",
                f"loop radius {_size(mm(s.radius))}", None,
                f"{at}, axis {_direction(s.axis)} (right-hand rule, base frame)",
                "copper")  # fmt: skip
        elif s.kind == "uniform":
            strength = float(np.linalg.norm(s.b))
            row(item, "provided",
                f"uniform field {strength:.4g} T along {_direction(np.asarray(s.b) / strength)}"
                if strength > 0 else "uniform field 0 T",
                "", None, "the scanner's or the coil system's field: nothing to buy")  # fmt: skip
        else:
            row(item, "provided", f"field map {Path(s.file).name}", "", None,
                f"whatever the map was measured or computed of, its origin at {centre}: "
                "nothing to buy beyond it")  # fmt: skip
    return out


def bill_of_materials(
    design: Design, assembly: RobotAssembly, parts: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    """Every item to buy or print for ``design`` (module docstring); ``parts`` are the
    parts table's rows (:func:`cad.build.build_parts`), for the printed parts' process,
    material and mass. [mm, g]"""
    tip, robot = design.tip, design.robot
    lay, d = assembly.actuator.layout, assembly.mounting.dims
    by_name = {p["name"]: p for p in parts}
    rows: list[dict[str, Any]] = []

    def bought(item: str, quantity: int, spec: str, size: str, mass: float | None, note: str,
               cut: float | None = None, material: str = "") -> None:  # fmt: skip
        rows.append(
            {"item": item, "kind": "bought", "quantity": quantity, "specification": spec,
             "size_mm": size, "cut_length_mm": None if cut is None else round(cut, 1),
             "process": "", "material": material, "mass_g": mass, "on_bed": "",
             "supports": "", "note": note}
        )  # fmt: skip

    ring = by_name.get("ring_magnet", {})
    bought(
        "ring_magnet", 2,
        f"ring magnet, {magnet_grade(tip.magnet_remanence)}, magnetised diametrically",
        f"OD {_size(mm(tip.magnet_outer_diameter))}, ID {_size(mm(tip.magnet_inner_diameter))}, "
        f"length {_size(mm(tip.magnet_length))}",
        ring.get("mass_g"),
        "glue each ring with its north at its piece's angle 0: on the distal piece the stop "
        f"key's centre line; on the proximal piece {d.key_angle_deg / 2:.1f} deg past the "
        "notch's edge the key bears on with the rings parallel (where the key's centre sits "
        "then); a compass or magnetic viewing film finds north",
        material="sintered NdFeB",
    )  # fmt: skip
    for row in field_rows(design):
        if row["kind"] == "bought":
            bought(row["item"], 1, row["specification"], row["size_mm"], row["mass_g"],
                   row["note"], material=row["material"])  # fmt: skip
        else:
            rows.append(_blank() | row)
    materials = {"catheter": robot.catheter, "wire": robot.wire}
    seated = cuts(design, lay, d)
    for name, c in seated.items():
        t = materials[name]
        bore = f", ID {_size(mm(t.inner_diameter))}" if t.inner_diameter > 0 else ""
        kind = "tube" if t.inner_diameter > 0 else "solid wire"
        glued = " and ".join(f"{s.engagement:.1f} mm in the {s.holder.replace('_', ' ')}"
                             for s in c.seats)  # fmt: skip
        bought(
            name, 1,
            f"{kind}, Young's modulus {_modulus(t.youngs_modulus)}",
            f"OD {_size(mm(t.outer_diameter))}{bore}",
            by_name.get(name, {}).get("mass_g"),
            f"buy at least {c.length + TRIM_ALLOWANCE_MM:.0f} mm; glued {glued}",
            cut=c.length,
        )  # fmt: skip
    for f in fasteners(lay):
        bought(f.name, f.quantity, f.standard, _size(f.diameter, f.length),
               by_name.get(f.name, {}).get("mass_g"), f.where, material="steel")  # fmt: skip
    bought(
        "adhesive", 1,
        "cyanoacrylate, medium viscosity (or a slow two-part epoxy)",
        "", None,
        "rings into their pockets; catheter and wire into their seats through the glue ports",
    )  # fmt: skip
    for p in parts:
        if not p["printed"]:
            continue
        setup = print_setup(p["name"])
        rows.append(
            {"item": p["name"], "kind": "printed", "quantity": p["quantity"],
             "specification": p["description"], "size_mm": _size(*p["size_mm"]),
             "cut_length_mm": None, "process": p["process"], "material": p["material"],
             "mass_g": p["mass_g"], "on_bed": setup.on_bed, "supports": setup.supports,
             "note": setup.why}
        )  # fmt: skip
    return rows


def bom_totals(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Counts and masses of the bill of materials: bought items and pieces, printed parts
    and pieces, printed mass, per process. [g]"""
    bought = [r for r in rows if r["kind"] == "bought"]
    printed = [r for r in rows if r["kind"] == "printed"]
    per_process: dict[str, float] = {}
    for r in printed:
        per_process[r["process"]] = per_process.get(r["process"], 0.0) + r["quantity"] * r["mass_g"]
    return {
        "bought_items": len(bought),
        "bought_pieces": sum(r["quantity"] for r in bought),
        "printed_parts": len(printed),
        "printed_pieces": sum(r["quantity"] for r in printed),
        "printed_mass_g": {k: round(v, 2) for k, v in per_process.items()},
    }


def write_bom_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    """Write ``bom.csv`` atomically (empty cells where a column does not apply)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=BOM_COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: "" if r[k] is None else r[k] for k in BOM_COLUMNS})
    write_text(path, buf.getvalue())
    return Path(path)

"""Export: STEP assembly with named parts, one STL per printed part, a 3MF print plate.

All files are in millimetres (STEP declares ``SI_UNIT(.MILLI.,.METRE.)``, the 3MF model
``unit="millimeter"``, STL has no unit and is in mm by convention). Each file is written
atomically: to a temporary file beside the target, then renamed, so a failed run leaves
no half-written file.
"""

from __future__ import annotations

import io
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np
import trimesh

from cad.assembly import RobotAssembly
from cad.errors import CadError
from cad.printing import print_setup
from cad.process import CadProcess
from design.atomic import atomic_path

PLATE_SPACING_MM = 6.0
PLATE_MARGIN_MM = 5.0


@dataclass(frozen=True)
class PartMesh:
    """A printed part's mesh in its print frame, as exported.

    vertices : shape (n, 3). [mm]
    triangles : shape (m, 3), indices into ``vertices``. [-]
    """

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    quantity: int


def export_step(assembly: RobotAssembly, path: Path, exploded: bool = False) -> Path:
    """Write the whole robot as one STEP assembly (AP214, mm), one named node per instance."""
    assy = assembly.to_cq(exploded=exploded)
    with atomic_path(path) as tmp:
        assy.export(str(tmp), exportType="STEP", unit="MM")
    return Path(path)


def export_stl(mesh: PartMesh, path: Path) -> Path:
    """Write one part as binary STL (mm)."""
    tm = trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False)
    data = tm.export(file_type="stl")
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


@dataclass(frozen=True)
class PlateItem:
    """One copy of a part on a print plate: translation of its print frame. [mm]"""

    part: str
    offset: tuple[float, float, float]


def arrange_plates(meshes: list[PartMesh], process: CadProcess) -> list[list[PlateItem]]:
    """Shelf-pack every copy of every part onto as few plates as the build area needs.

    Parts keep their print orientation; each footprint is its bounding rectangle plus
    ``PLATE_SPACING_MM``. Raises :class:`~cad.errors.CadError` if a part alone does not fit.
    """
    bx, by, _ = process.build_volume_mm
    items = []
    for m in meshes:
        lo, hi = m.vertices.min(axis=0), m.vertices.max(axis=0)
        size = hi - lo
        if size[0] > bx - 2 * PLATE_MARGIN_MM or size[1] > by - 2 * PLATE_MARGIN_MM:
            raise CadError(
                f"print plate: part {m.name} footprint must fit the {process.printer} bed "
                f"({bx:g} x {by:g} mm); got {size[0]:.1f} x {size[1]:.1f} mm"
            )
        items += [(m.name, lo, size)] * m.quantity
    items.sort(key=lambda it: (-it[2][1], -it[2][0]))
    plates: list[list[PlateItem]] = [[]]
    x = y = PLATE_MARGIN_MM
    row = 0.0
    for name, lo, size in items:
        if x + size[0] > bx - PLATE_MARGIN_MM:
            x, y, row = PLATE_MARGIN_MM, y + row + PLATE_SPACING_MM, 0.0
        if y + size[1] > by - PLATE_MARGIN_MM:
            plates.append([])
            x, y, row = PLATE_MARGIN_MM, PLATE_MARGIN_MM, 0.0
        plates[-1].append(PlateItem(name, (x - lo[0], y - lo[1], -lo[2])))
        x += size[0] + PLATE_SPACING_MM
        row = max(row, size[1])
    return plates


def threemf_bytes(
    meshes: dict[str, PartMesh], plate: list[PlateItem], process: CadProcess | None = None
) -> bytes:
    """A 3MF package (core specification 1.3): one object per part, one build item per
    copy; each object carries its print set-up (:mod:`cad.printing`: the face on the bed,
    supports, why) and the process as metadata (``ringpair:`` names)."""
    ids = {name: k + 1 for k, name in enumerate(sorted({it.part for it in plate}))}
    out = io.StringIO()
    out.write('<?xml version="1.0" encoding="UTF-8"?>\n')
    out.write(
        '<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">\n'
    )
    out.write(' <metadata name="Application">ringpair cad</metadata>\n <resources>\n')
    for name, oid in ids.items():
        m = meshes[name]
        setup = print_setup(name)
        meta = {
            "ringpair:on_bed": setup.on_bed,
            "ringpair:supports": setup.supports,
            "ringpair:orientation": setup.why,
            **({"ringpair:process": process.name} if process is not None else {}),
        }
        out.write(f'  <object id="{oid}" name={quoteattr(name)} type="model">\n')
        out.write("   <metadatagroup>\n")
        out.writelines(
            f"    <metadata name={quoteattr(k)}>{escape(v)}</metadata>\n" for k, v in meta.items()
        )
        out.write("   </metadatagroup>\n   <mesh>\n")
        out.write("    <vertices>\n")
        out.writelines(
            f'     <vertex x="{x:.5f}" y="{y:.5f}" z="{z:.5f}"/>\n' for x, y, z in m.vertices
        )
        out.write("    </vertices>\n    <triangles>\n")
        out.writelines(f'     <triangle v1="{a}" v2="{b}" v3="{c}"/>\n' for a, b, c in m.triangles)
        out.write("    </triangles>\n   </mesh>\n  </object>\n")
    out.write(" </resources>\n <build>\n")
    for it in plate:
        dx, dy, dz = it.offset
        transform = f"1 0 0 0 1 0 0 0 1 {dx:.4f} {dy:.4f} {dz:.4f}"
        out.write(f'  <item objectid="{ids[it.part]}" transform="{transform}"/>\n')
    out.write(" </build>\n</model>\n")
    content_types = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">\n'
        ' <Default Extension="rels" '
        'ContentType="application/vnd.openxmlformats-package.relationships+xml"/>\n'
        ' <Default Extension="model" '
        'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>\n'
        "</Types>\n"
    )
    rels = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">\n'
        ' <Relationship Target="/3D/3dmodel.model" Id="rel0" '
        'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>\n'
        "</Relationships>\n"
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("[Content_Types].xml", content_types)
        z.writestr("_rels/.rels", rels)
        z.writestr("3D/3dmodel.model", out.getvalue())
    return buf.getvalue()


def export_3mf(
    meshes: dict[str, PartMesh],
    plate: list[PlateItem],
    path: Path,
    process: CadProcess | None = None,
) -> Path:
    """Write one print plate as 3MF (mm), its parts' print set-ups as metadata."""
    data = threemf_bytes(meshes, plate, process)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def plate_extent(meshes: dict[str, PartMesh], plate: list[PlateItem]) -> tuple[float, float, float]:
    """Bounding size x, y, z of everything on a plate. [mm]"""
    lo = np.full(3, math.inf)
    hi = np.full(3, -math.inf)
    for it in plate:
        v = meshes[it.part].vertices + np.asarray(it.offset)
        lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
    size = hi - lo
    return (float(size[0]), float(size[1]), float(size[2]))

"""A real slicer reads the 3MF plates: PrusaSlicer, headless, on a plate of small parts.

Issue 52: the STL and 3MF files were only read back by the project's own code. Here
``prusa-slicer`` (the Debian package) slices a plate made by :func:`cad.export.threemf_bytes`
in the parts' print orientation, supports off as the print set-up says, on the FDM
process's bed, and the G-code's estimated print time and the slicer's warnings are read.
Only the small parts go on the plate so the slice takes seconds (the whole FDM plate: 24 s
of CPU, these two: about 4 s). Skipped, saying so, where PrusaSlicer is not installed.
"""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest
import trimesh

from cad.build import CadReport
from cad.export import PartMesh, arrange_plates, threemf_bytes
from cad.printing import PRINT_SETUP
from cad.process import FDM

SLICER = shutil.which("prusa-slicer")
SMALL = ("shaft_clip", "worm_bushing")


def _time_s(gcode: str) -> float:
    """The G-code's estimated print time (normal mode). [s]"""
    m = re.search(r"estimated printing time \(normal mode\) = ([0-9dhms ]+)", gcode)
    assert m, "no print time in the G-code"
    units = {"d": 86400, "h": 3600, "m": 60, "s": 1}
    return float(sum(int(n) * units[u] for n, u in re.findall(r"(\d+)([dhms])", m.group(1))))


@pytest.mark.skipif(SLICER is None, reason="PrusaSlicer is not installed (Debian package "
                    "'prusa-slicer'; .ci/run installs it)")  # fmt: skip
def test_prusaslicer_slices_a_plate_headless_without_warnings(fdm_build: CadReport, tmp_path):
    meshes = {}
    for name in SMALL:
        mesh = trimesh.load(fdm_build.out_dir / "stl" / f"{name}.stl", force="mesh")
        meshes[name] = PartMesh(name, np.asarray(mesh.vertices), np.asarray(mesh.faces), 1)
        assert PRINT_SETUP[name].supports == "none"
    (plate,) = arrange_plates(list(meshes.values()), FDM)
    path = tmp_path / "small.3mf"
    path.write_bytes(threemf_bytes(meshes, plate, FDM))
    bx, by, _ = FDM.build_volume_mm
    gcode = tmp_path / "small.gcode"
    done = subprocess.run(
        [SLICER, "--export-gcode", "--dont-arrange",
         "--bed-shape", f"0x0,{bx:g}x0,{bx:g}x{by:g},0x{by:g}",
         "--output", str(gcode), str(path)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    log = done.stdout + done.stderr
    assert done.returncode == 0, log[-2000:]
    warnings = [
        line for line in log.splitlines()
        if re.search(r"\b(warning|error)\b", line, re.I) and "[trace]" not in line
    ]  # fmt: skip
    assert warnings == [], warnings
    text = gcode.read_text()
    seconds = _time_s(text)
    print(f"PrusaSlicer: {', '.join(SMALL)} in {seconds / 60:.0f} min")
    assert 60 < seconds < 24 * 3600  # minutes to hours, not zero or days
    assert "; support_material = 0" in text

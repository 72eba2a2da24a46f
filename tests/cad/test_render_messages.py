"""VTK's own messages while rendering: none leak onto stderr raw (colour codes, C++ source
lines); what VTK says comes out as one warning in plain words."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from vtkmodules.vtkCommonCore import vtkOutputWindow

from cad.render import RenderWarning, vtk_messages

RENDER_WITHOUT_DISPLAY = """
import pyvista as pv
import cad.render
with cad.render.vtk_messages():
    pl = pv.Plotter(off_screen=True)
    pl.add_mesh(pv.Sphere())
    image = pl.screenshot(None, return_img=True)
print(image.shape, image.std() > 5)
"""


def test_rendering_without_a_display_prints_nothing_on_stderr():
    # No DISPLAY: VTK's default window would try X first and print, with colour codes,
    # "bad X server connection. DISPLAY=" before falling back to EGL.
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    done = subprocess.run(
        [sys.executable, "-c", RENDER_WITHOUT_DISPLAY],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=True,
    )
    assert done.stdout.strip().endswith("True")  # a picture was drawn
    assert done.stderr == ""


def test_what_vtk_says_is_one_warning_in_plain_words(capfd):
    alert = "Generic Warning: In vtkSomething.cxx, line 12\nthe mesh has no normals"
    with pytest.warns(RenderWarning) as caught, vtk_messages():
        vtkOutputWindow.GetInstance().DisplayWarningText(alert)
    assert len(caught) == 1
    message = str(caught[0].message)
    assert "the mesh has no normals" in message and ".cxx" not in message
    assert capfd.readouterr().err == ""

"""Offscreen renders (PNG) of every part, the assembly, the tip and exploded views.

pyvista renders without a display through EGL (Debian: ``libgl1 libegl1``; no X server,
no ``start_xvfb``). Each picture is written atomically. Geometry in millimetres, base
frame for assembly views, print frame for part views; z is up in every picture.

VTK prints its own messages from C++ on stderr, with colour codes (without a display it
first tried X: "bad X server connection. DISPLAY="). Without a display the EGL window is
asked for directly, and :func:`render_all` captures whatever VTK still says and passes it
on as one :class:`RenderWarning` in plain words.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyvista as pv
from PIL import Image

from cad.assembly import Colour, Instance, RobotAssembly
from cad.meshing import location_matrix, tessellate
from cad.solids import box
from cad.sources import bodiless, source_meshes
from design.atomic import atomic_path
from design.records import Design

pv.OFF_SCREEN = True
if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
    # VTK's default window wants X and warns before it falls back to EGL; read when the
    # first render window is made, so setting it here, after the import, is in time.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


class RenderWarning(UserWarning):
    """Something VTK said while rendering, in plain words."""


@contextmanager
def vtk_messages() -> Iterator[None]:
    """Keep VTK's own stderr output (C++ logger, colour codes) out of the terminal while
    the block runs; what it said comes out afterwards as one :class:`RenderWarning`."""
    with pv.vtk_verbosity("off"), pv.VtkErrorCatcher(send_to_logging=False) as caught:
        yield
    said = dict.fromkeys(e.alert.strip().splitlines()[-1] for e in caught.events if e.alert)
    if said:
        warnings.warn(
            "the renders may be wrong or missing; VTK said: " + "; ".join(said),
            RenderWarning,
            stacklevel=3,
        )


BACKGROUND_TOP = (1.0, 1.0, 1.0)
BACKGROUND_BOTTOM = (0.84, 0.87, 0.92)
TEXT = (0.12, 0.12, 0.18)
NORTH = (0.86, 0.16, 0.16)
SOUTH = (0.16, 0.32, 0.86)
SCENE_WINDOW = (1600, 1200)
PART_WINDOW = (1200, 900)
RENDER_DEFLECTION_MM = 0.05
FEATURE_ANGLE_DEG = 35.0

Eye = tuple[float, float, float]


@dataclass
class MeshCache:
    """Render meshes of each part in its own frame, with normals and colours. [mm]"""

    meshes: dict[str, list[tuple[pv.PolyData, Colour]]]

    @classmethod
    def of(
        cls,
        assembly: RobotAssembly,
        meshes: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    ) -> MeshCache:
        """Use the given (vertices, triangles) per part where available (the exported
        meshes), tessellate the rest. The ring magnet is split into its north (local +X,
        red) and south (blue) halves: it is magnetised across its diameter."""
        meshes = meshes or {}
        out: dict[str, list[tuple[pv.PolyData, Colour]]] = {}
        for name, part in assembly.parts.items():
            size = max(part.solid.BoundingBox().DiagonalLength, 1.0)
            deflection = min(RENDER_DEFLECTION_MM, size / 400)
            if name == "ring_magnet":
                half = box((0, 100), (-100, 100), (-100, 100))
                out[name] = [
                    (_surface(*tessellate(part.solid.intersect(half), deflection)), NORTH),
                    (_surface(*tessellate(part.solid.cut(half), deflection)), SOUTH),
                ]
            elif name in meshes:
                out[name] = [(_surface(*meshes[name]), part.colour)]
            else:
                out[name] = [(_surface(*tessellate(part.solid, deflection)), part.colour)]
        return cls(out)


def _surface(vertices: np.ndarray, triangles: np.ndarray) -> pv.PolyData:
    """PolyData with point normals split at sharp edges (computed once per part)."""
    faces = np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel()
    poly = pv.PolyData(np.asarray(vertices, dtype=float), faces)
    return poly.compute_normals(
        split_vertices=True, feature_angle=FEATURE_ANGLE_DEG, auto_orient_normals=False
    )


def _placed(cache: MeshCache, inst: Instance, exploded: bool) -> list[tuple[pv.PolyData, Colour]]:
    m = location_matrix(inst.location)
    if exploded:
        m[:3, 3] += np.asarray(inst.explode)
    return [(mesh.transform(m, inplace=False), colour) for mesh, colour in cache.meshes[inst.part]]


def _plotter(window: tuple[int, int]) -> pv.Plotter:
    pl = pv.Plotter(off_screen=True, window_size=list(window), lighting="three lights")
    pl.set_background(BACKGROUND_BOTTOM, top=BACKGROUND_TOP)
    pl.enable_anti_aliasing("msaa", multi_samples=8)
    return pl


def _add(pl: pv.Plotter, mesh: pv.PolyData, colour: Colour, opacity: float = 1.0) -> None:
    pl.add_mesh(
        mesh,
        color=colour,
        opacity=opacity,
        smooth_shading=True,
        specular=0.3,
        specular_power=25.0,
        ambient=0.18,
        diffuse=0.8,
    )


def _view(pl: pv.Plotter, eye: Eye, zoom: float) -> None:
    """Camera on the ray from the scene's centre towards ``eye``, z up, framing all."""
    centre = np.asarray(pl.center)
    pl.camera_position = [tuple(centre + np.asarray(eye) * 1e3), tuple(centre), (0, 0, 1)]
    pl.reset_camera()
    pl.camera.zoom(zoom)


def _save(pl: pv.Plotter, path: Path, title: str) -> Path:
    pl.add_text(title, position="upper_left", font_size=12, color=TEXT)
    img = pl.screenshot(None, return_img=True)
    pl.close()
    with atomic_path(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")
    return Path(path)


# Views that show a part's features best (print frame): the helical grooves face these.
PART_EYES: dict[str, Eye] = {
    "mounting_piece_proximal": (0.5, 1.0, 0.45),
    "mounting_piece_distal": (0.5, -1.0, 0.45),
}


def render_part(cache: MeshCache, assembly: RobotAssembly, name: str, path: Path) -> Path:
    """One part in its print frame (as it sits on the bed), size in the title."""
    pl = _plotter(PART_WINDOW)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for mesh, colour in cache.meshes[name]:
        _add(pl, mesh, colour)
        b = np.asarray(mesh.bounds).reshape(3, 2)
        lo, hi = np.minimum(lo, b[:, 0]), np.maximum(hi, b[:, 1])
    _view(pl, PART_EYES.get(name, (1.0, -1.35, 0.95)), zoom=1.0)
    part = assembly.parts[name]
    kind = "print frame" if part.printed else "bought part"
    size = " x ".join(f"{s:.1f}" for s in hi - lo)
    return _save(pl, path, f"{name}: {size} mm ({kind}), x{part.quantity}")


def render_scene(
    cache: MeshCache,
    assembly: RobotAssembly,
    path: Path,
    title: str,
    eye: Eye,
    group: str | None = None,
    exploded: bool = False,
    transparent: tuple[str, ...] = (),
    x_range: tuple[float, float] | None = None,
    section: bool = False,
    zoom: float = 1.0,
    extra: list[tuple[pv.PolyData, Colour]] | None = None,
) -> Path:
    """Instances (all, or one ``group``) in the base frame, with ``extra`` surfaces (the
    field sources, :mod:`cad.sources`).

    exploded : Move every instance by its explode offset.
    transparent : Parts drawn see-through (e.g. the lid).
    x_range : Keep only what lies within this base-frame x range (close-ups). [mm]
    section : Cut everything at the plane z = 0 (through the robot axis) and keep the
        lower half, capped, to show what is inside.
    """
    pl = _plotter(SCENE_WINDOW)
    big = 1e4
    for inst in assembly.instances:
        if group is not None and inst.group != group:
            continue
        opacity = 0.3 if inst.part in transparent else 1.0
        for mesh, colour in _placed(cache, inst, exploded):
            if x_range is not None:
                if mesh.bounds[1] < x_range[0] or mesh.bounds[0] > x_range[1]:
                    continue
                if mesh.bounds[0] < x_range[0] or mesh.bounds[1] > x_range[1]:
                    bounds = (x_range[0], x_range[1], -big, big, -big, big)
                    mesh = mesh.clip_box(bounds, invert=False).extract_surface(algorithm=None)
            if section:
                mesh = _section(mesh)
            if mesh.n_points == 0:
                continue
            _add(pl, mesh, colour, opacity)
    for mesh, colour in extra or []:
        _add(pl, mesh, colour)
    _view(pl, eye, zoom)
    return _save(pl, path, title)


def _section(mesh: pv.PolyData) -> pv.PolyData:
    """Keep the half below z = 0, capped where the surface is closed."""
    whole = mesh.extract_surface(algorithm=None).clean()
    try:
        cut = whole.clip_closed_surface(normal=(0, 0, -1), origin=(0, 0, 0))
    except ValueError:  # open (clipped) surfaces: no cap
        cut = whole.clip(normal=(0, 0, 1), origin=(0, 0, 0)).extract_surface(algorithm=None)
    if cut.n_points == 0:
        return cut
    return cut.compute_normals(split_vertices=True, feature_angle=FEATURE_ANGLE_DEG)


def tip_x_range(assembly: RobotAssembly) -> tuple[float, float]:
    """Base-frame x extent of the two mounting pieces plus a margin. [mm]"""
    xs = []
    for inst in assembly.instances:
        if inst.part.startswith("mounting_piece"):
            bb = assembly.placed(inst).BoundingBox()
            xs += [bb.xmin, bb.xmax]
    return min(xs) - 4.0, max(xs) + 2.0


def render_all(
    assembly: RobotAssembly,
    out_dir: Path,
    meshes: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    design: Design | None = None,
) -> list[Path]:
    """Every picture: each printed part and the ring; the robot; the actuator; the tip,
    whole and in section; exploded actuator and tip; with ``design``, the set-up (the
    robot and its field sources to scale). ``meshes``: (vertices, triangles) per part to
    reuse (the exported meshes). Returns the files written."""
    with vtk_messages():
        return _render_all(assembly, Path(out_dir), meshes, design)


def _render_all(
    assembly: RobotAssembly,
    out_dir: Path,
    meshes: dict[str, tuple[np.ndarray, np.ndarray]] | None,
    design: Design | None,
) -> list[Path]:
    cache = MeshCache.of(assembly, meshes)
    files: list[Path] = []
    for name, part in assembly.parts.items():
        if part.printed or name == "ring_magnet":
            files.append(render_part(cache, assembly, name, out_dir / "parts" / f"{name}.png"))
    t1, t2 = assembly.theta1_deg, assembly.theta2_deg
    lo, hi = tip_x_range(assembly)
    scenes = [
        dict(
            path=out_dir / "assembly.png",
            title=f"ringpair robot (mm, base frame): theta1 = {t1:g} deg, theta2 = {t2:g} deg",
            eye=(0.35, -1.0, 0.75),
            transparent=("lid",),
            zoom=1.25,
        ),
        dict(
            path=out_dir / "actuator.png",
            title="actuator: two self-locking worm drives, lid see-through",
            eye=(0.6, -0.8, 1.8),
            group="actuator",
            transparent=("lid",),
            zoom=1.15,
        ),
        dict(
            path=out_dir / "exploded.png",
            title="actuator, exploded",
            eye=(0.9, -1.2, 0.9),
            group="actuator",
            exploded=True,
            zoom=1.1,
        ),
        dict(
            path=out_dir / "tip.png",
            title="tip: proximal piece (catheter, theta2) and distal piece (wire, theta1)",
            eye=(0.45, -1.0, 0.55),
            group="tip",
            x_range=(lo, hi),
            zoom=1.3,
        ),
        dict(
            path=out_dir / "tip_section.png",
            title=f"tip in section: rings (red = north) at theta1 = {t1:g}, theta2 = {t2:g} deg",
            eye=(0.2, -0.35, 1.0),
            group="tip",
            x_range=(lo, hi),
            section=True,
            zoom=1.3,
        ),
        dict(
            path=out_dir / "tip_exploded.png",
            title="tip, exploded: catheter, proximal piece, rings, distal piece, wire",
            eye=(0.45, -1.0, 0.55),
            group="tip",
            exploded=True,
            x_range=(lo - 6.0, hi + 14.0),
            zoom=1.3,
        ),
    ]
    if design is not None:
        named = ", ".join(["magnets red = north", *bodiless(design)])
        scenes.append(
            dict(
                path=out_dir / "setup.png",
                title=f"set-up to scale (mm): the straight robot and its field ({named})",
                eye=(0.3, -1.0, 0.55),
                transparent=("lid",),
                extra=source_meshes(design),
                zoom=1.2,
            )
        )
    for scene in scenes:
        files.append(render_scene(cache, assembly, **scene))  # type: ignore[arg-type]
    return files

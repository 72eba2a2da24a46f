"""Workspace pictures (matplotlib, written atomically as PNG). Millimetres and degrees."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

from design.atomic import atomic_path  # noqa: E402
from design.branches import Branch  # noqa: E402
from design.equilibrium import Equilibria  # noqa: E402
from design.params import Design  # noqa: E402
from design.workspace import Workspace  # noqa: E402

MM = 1e3
REACH = "#1f77b4"
LOOP = "#d62728"
NEUTRAL = "#2ca02c"
FLAT = 1e-6
"""A panel whose values stay within this of zero on every branch is left out. [mm or deg]"""


def _save(fig: plt.Figure, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=130, bbox_inches="tight")
    plt.close(fig)


def _magnet_outline(ax: plt.Axes, design: Design, axes: tuple[int, int]) -> None:
    """Outline of the external cylinder projected on a base-frame plane (axis along x/y/z)."""
    ext = design.external_magnet
    axis = np.abs(np.asarray(ext.magnetization))
    half = np.where(axis > 0.5, ext.length / 2, ext.diameter / 2)
    c = np.asarray(ext.center)
    i, j = axes
    ax.add_patch(
        Rectangle(
            ((c[i] - half[i]) * MM, (c[j] - half[j]) * MM),
            2 * half[i] * MM,
            2 * half[j] * MM,
            facecolor="#bbbbbb",
            edgecolor="#555555",
            label="external magnet",
        )
    )


def plot_projection(
    ws: Workspace, design: Design, path: Path, axes: tuple[int, int], title: str
) -> None:
    """Reachable tip positions and the set-up seen on one base-frame plane."""
    names = "xyz"
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    pts = ws.reachable * MM
    i, j = axes
    ax.plot(
        [0, design.robot.free_length * MM], [0, 0], color="#444444", lw=2, label="straight robot"
    )
    ax.scatter(pts[:, i], pts[:, j], s=3, color=REACH, label="reachable tips")
    _magnet_outline(ax, design, axes)
    ax.plot(ws.rest_position[i] * MM, ws.rest_position[j] * MM, "k+", ms=12, label="rest")
    ax.set_xlabel(f"{names[i]} [mm]")
    ax.set_ylabel(f"{names[j]} [mm]")
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    _save(fig, path)


def plot_section(ws: Workspace, path: Path) -> None:
    """The workspace looking along the base x axis: reachable set, loops, disc, maximum."""
    fig, ax = plt.subplots(figsize=(6, 6))
    pts = (ws.reachable - ws.rest_position) * MM
    ax.scatter(pts[:, 1], pts[:, 2], s=3, color=REACH, alpha=0.5, label="reachable tips")
    for eq, color, label in (
        (ws.parallel, LOOP, "parallel rings (boundary)"),
        (ws.antiparallel, NEUTRAL, "antiparallel rings (neutral)"),
    ):
        loop = (eq.position[eq.converged] - ws.rest_position) * MM
        ax.plot(
            np.append(loop[:, 1], loop[:1, 1]),
            np.append(loop[:, 2], loop[:1, 2]),
            color=color,
            lw=1.5,
            label=label,
        )
    ax.add_patch(
        Circle(
            (0, 0),
            ws.disc_radius * MM,
            fill=False,
            ls="--",
            color="k",
            label=f"largest disc, r = {ws.disc_radius * MM:.2f} mm",
        )
    )
    tip = ws.max_direction * ws.max_deflection * MM
    ax.annotate(
        "", xy=(tip[1], tip[2]), xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": "k"}
    )
    ax.text(tip[1], tip[2], f" max {ws.max_deflection * MM:.2f} mm", fontsize=8)
    ax.set_xlabel("y deflection [mm]")
    ax.set_ylabel("z deflection [mm]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title("Workspace seen along the base x axis")
    ax.legend(loc="lower left", fontsize=8)
    _save(fig, path)


def plot_deflection(sweep: Equilibria, ws: Workspace, path: Path) -> None:
    """Deflection against ring angle: theta1 swept with theta2 = 0 (the paper's experiment)
    and the parallel rings (theta1 = theta2) turned together."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    d = (sweep.position - ws.rest_position) * MM
    t = np.rad2deg(sweep.command[:, 0])
    ax.plot(t, np.linalg.norm(d, axis=1), "k-", lw=2, label="|deflection|, theta2 = 0")
    ax.plot(t, d[:, 1], "-", color=REACH, label="y, theta2 = 0")
    ax.plot(t, d[:, 2], "-", color=NEUTRAL, label="z, theta2 = 0")
    dp = (ws.parallel.position - ws.rest_position) * MM
    ax.plot(
        np.rad2deg(ws.parallel.command[:, 0]),
        np.linalg.norm(dp, axis=1),
        "--",
        color=LOOP,
        label="|deflection|, theta1 = theta2",
    )
    ax.set_xlabel("theta1 [deg]")
    ax.set_ylabel("tip deflection [mm]")
    ax.set_xlim(0, 360)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Tip deflection against ring angle")
    _save(fig, path)


def write_workspace_plots(
    ws: Workspace, sweep: Equilibria, design: Design, out_dir: str | os.PathLike[str]
) -> list[Path]:
    """All workspace pictures into ``out_dir``; returns the paths written."""
    out = Path(out_dir)
    paths = [out / "top.png", out / "side.png", out / "section.png", out / "deflection.png"]
    plot_projection(ws, design, paths[0], (0, 1), "Top view (x-y plane)")
    plot_projection(ws, design, paths[1], (0, 2), "Side view (x-z plane)")
    plot_section(ws, paths[2])
    plot_deflection(sweep, ws, paths[3])
    return paths


def plot_branch_diagram(
    path_states: Equilibria, others: list[Branch], load_factors: np.ndarray, title: str,
    path: Path,
) -> None:
    """A branch diagram: tip y, tip z and (with torsion) the rings' relative angle against
    the load factor; the state the robot reaches as its loads are brought up, snaps
    marked, beside the other branches (solid where stable, dashed where unstable)."""
    torsion = not np.allclose(path_states.tip_angles, path_states.command, equal_nan=True)
    panels = [
        ("tip y [mm]", lambda s: s.position[:, 1] * MM),
        ("tip z [mm]", lambda s: s.position[:, 2] * MM),
    ]
    if torsion:
        panels.append(
            ("theta1 - theta2 at the tip [deg]",
             lambda s: np.rad2deg(s.tip_angles[:, 0] - s.tip_angles[:, 1])),
        )
    # A quantity that stays zero on every branch (a set-up symmetric about the x-y
    # plane) says nothing: its panel is left out.
    panels = [
        p for p in panels
        if any(np.nanmax(np.abs(p[1](s)), initial=0.0) > FLAT for s in (path_states, *others))
    ] or panels[:1]
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.8), squeeze=False)
    drawn: set[str] = set()

    def label(name: str, values: np.ndarray) -> str | None:
        """Each legend entry once, and only for what is drawn."""
        if name in drawn or not np.isfinite(values).any():
            return None
        drawn.add(name)
        return name

    for ax, (ylabel, value) in zip(axes[0], panels, strict=True):
        for branch in others:
            v = value(branch)
            for stable, style, name in ((True, "-", "other equilibria, stable"),
                                        (False, "--", "other equilibria, unstable")):
                part = np.where(branch.stable == stable, v, np.nan)
                ax.plot(load_factors, part, style, color="#888888", lw=1.2,
                        label=label(name, part))
        v = value(path_states)
        ax.plot(load_factors, v, "-", color=REACH, lw=2.5,
                label=label("the state (load ramp)", v))
        snaps = np.flatnonzero(np.diff(path_states.snapped.astype(int)) > 0) + 1
        ax.plot(load_factors[snaps], v[snaps], "v", color=LOOP, ms=8,
                label=label("snap", v[snaps]))
        ax.set_xlabel("load factor (magnet brought up) [-]")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    _save(fig, path)

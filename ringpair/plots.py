"""Every figure of ringpair (matplotlib, written atomically as PNG): workspace pictures,
branch diagrams, Pareto fronts, the tolerance spread and the diagnosis's residuals.
Millimetres and degrees on the axes; SI in the arguments unless they say otherwise."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend is chosen before pyplot loads)
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

from design.atomic import atomic_path  # noqa: E402
from design.branches import Branch  # noqa: E402
from design.controllable import Controllable  # noqa: E402
from design.equilibrium import Equilibria  # noqa: E402
from design.paths import PathSchedule  # noqa: E402
from design.records import Design  # noqa: E402
from design.units import MM  # noqa: E402
from design.workspace import Workspace  # noqa: E402
from ringpair.tables import PARETO_UNITS, objective_in_report_units  # noqa: E402

if TYPE_CHECKING:
    from optimize.fitting.diagnose import Diagnosis, Fit
    from optimize.fitting.measurements import Measurements
    from optimize.sizing.nlp import OptimizationResult
    from optimize.sizing.pareto import ParetoPoint, ParetoResult
    from optimize.sizing.studyfile import Study

REACH = "#1f77b4"
LOOP = "#d62728"
NEUTRAL = "#2ca02c"
FLAT = 1e-6
"""A panel whose values stay within this of zero on every branch is left out. [mm or deg]"""


def _save(fig: plt.Figure, path: Path, dpi: int = 130) -> None:
    """Write ``fig`` to ``path`` as PNG, atomically, and close it."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)


def _magnet_outline(ax: plt.Axes, design: Design, axes: tuple[int, int]) -> None:
    """Outline of the external cylinder projected on a base-frame plane (axis along x/y/z)."""
    ext = design.external_magnet
    if ext is None:
        return
    axis = np.abs(np.asarray(ext.magnetization))
    half = np.where(axis > 0.5, ext.length / 2, ext.diameter / 2)
    c = np.asarray(ext.center)
    i, j = axes
    ax.add_patch(
        Rectangle(
            ((c[i] - half[i]) / MM, (c[j] - half[j]) / MM),
            2 * half[i] / MM,
            2 * half[j] / MM,
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
    pts = ws.reachable / MM
    i, j = axes
    ax.plot(
        [0, design.robot.free_length / MM], [0, 0], color="#444444", lw=2, label="straight robot"
    )
    ax.scatter(pts[:, i], pts[:, j], s=3, color=REACH, label="reachable tips")
    _magnet_outline(ax, design, axes)
    ax.plot(ws.rest_position[i] / MM, ws.rest_position[j] / MM, "k+", ms=12, label="straight tip")
    ax.plot(ws.home.position[i] / MM, ws.home.position[j] / MM, "kx", ms=9, label="home")
    ax.set_xlabel(f"{names[i]} [mm]")
    ax.set_ylabel(f"{names[j]} [mm]")
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    _save(fig, path)


def plot_path(schedule: PathSchedule, path: Path, title: str) -> None:
    """A steered path: the requested and the driven tip, looking along the base x axis
    (left), in 3-D (middle), and the schedule of ring angles (right)."""
    fig = plt.figure(figsize=(16, 4.8))
    fig.subplots_adjust(wspace=0.4)
    ax = fig.add_subplot(1, 3, 1)
    space = fig.add_subplot(1, 3, 2, projection="3d")
    angles = fig.add_subplot(1, 3, 3)
    want = schedule.points / MM
    if schedule.closed:
        want = np.vstack([want, want[:1]])
    ax.plot(want[:, 0], want[:, 1], "k--", lw=1, label="requested path")
    driven = schedule.driven[:, 1:] / MM
    ax.plot(driven[:, 0], driven[:, 1], color=REACH, lw=1.5, label="driven tip (simulated)")
    tip = schedule.position[:, 1:] / MM
    ok = schedule.reached & ~schedule.snapped
    ax.plot(tip[ok, 0], tip[ok, 1], "o", ms=3, color=REACH, label="at the path's points")
    if (~schedule.reached).any():
        miss = ~schedule.reached
        ax.plot(tip[miss, 0], tip[miss, 1], "x", color=LOOP, label="out of reach: closest point")
    if schedule.snapped.any():
        ax.plot(*tip[schedule.snapped].T, "s", mfc="none", color=LOOP, label="snapped on the way")
    ax.plot(want[0, 0], want[0, 1], ">", color="k", ms=8, label="start")
    ax.set_xlabel("y [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=7)
    ax.set_title("the tip, looking along the robot (base x axis)", fontsize=9)
    fig.suptitle(title, fontsize=10)
    cloud = schedule.driven / MM
    space.plot(*cloud.T, color=REACH, lw=1.2, label="driven tip")
    spot = schedule.position / MM
    space.scatter(*spot[ok].T, s=6, color=REACH)
    if (~ok).any():
        space.scatter(*spot[~ok].T, s=12, marker="x", color=LOOP)
    span = np.nanmax(np.ptp(cloud[np.isfinite(cloud).all(axis=1)], axis=0)[1:]) or 1.0
    middle = np.nanmean(cloud, axis=0)
    space.set_xlim(middle[0] - span / 2, middle[0] + span / 2)
    space.set_ylim(middle[1] - span / 2, middle[1] + span / 2)
    space.set_zlim(middle[2] - span / 2, middle[2] + span / 2)
    space.set_xlabel("x [mm]")
    space.set_ylabel("y [mm]")
    space.set_zlabel("z [mm]", labelpad=2)
    space.set_title("the tip in 3-D (base frame)", fontsize=9)
    step = np.arange(1, len(schedule.points) + 1)
    for k, (name, color, style) in enumerate(
        (("theta1 (wire)", REACH, "o-"), ("theta2 (catheter)", LOOP, ".--"))
    ):
        angles.plot(step, np.rad2deg(schedule.theta[:, k]), style, ms=3, color=color, label=name)
    angles.set_xlabel("step along the path")
    angles.set_ylabel("ring angle [deg]")
    angles.grid(alpha=0.3)
    angles.legend(fontsize=8)
    angles.set_title("schedule of ring angles", fontsize=9)
    _save(fig, path)


def plot_controllable(ws: Workspace, ctl: Controllable, path: Path, model: str) -> None:
    """The controllable workspace looking along the base x axis: the grid's tips that can
    be steered to from home without a snap, the others, the disc about home and the
    controllable cells' covered disc (deflection from the straight tip)."""
    fig, ax = plt.subplots(figsize=(6.4, 6))
    tip = (ctl.position - ws.rest_position)[:, :, 1:] / MM
    home = (ws.home.position - ws.rest_position)[1:] / MM
    ok = np.isfinite(tip).all(axis=2)
    steerable, behind = tip[ok & ctl.controllable], tip[ok & ~ctl.controllable]
    ax.scatter(steerable[:, 0], steerable[:, 1], s=4, color=REACH, label="steerable from home")
    if len(behind):
        ax.scatter(behind[:, 0], behind[:, 1], s=6, color=LOOP, label="only through a snap")
    for radius, style, label in (
        (ctl.disc_radius, "--", "the disc"),
        (ctl.covered_disc_radius, ":", "covered by steerable cells"),
    ):
        ax.add_patch(
            Circle(
                tuple(home),
                radius / MM,
                fill=False,
                ls=style,
                color="k",
                label=f"{label}, r = {radius / MM:.2f} mm",
            )
        )
    ax.plot(0, 0, "k+", ms=10, label="straight tip")
    ax.plot(*home, "kx", ms=8, label=f"home, droop {ws.droop / MM:.2f} mm")
    ax.set_xlabel("y deflection [mm]")
    ax.set_ylabel("z deflection [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.set_title(
        f"Controllable workspace ({model} model): {100 * ctl.fraction:.0f} % of the configurations",
        fontsize=9,
    )
    ax.legend(loc="lower left", fontsize=8)
    _save(fig, path)


def plot_section(ws: Workspace, path: Path) -> None:
    """The workspace looking along the base x axis: reachable set, loops, disc, maximum."""
    fig, ax = plt.subplots(figsize=(6, 6))
    pts = (ws.reachable - ws.rest_position) / MM
    ax.scatter(pts[:, 1], pts[:, 2], s=3, color=REACH, alpha=0.5, label="reachable tips")
    for eq, color, label in (
        (ws.parallel, LOOP, "parallel rings (boundary)"),
        (ws.antiparallel, NEUTRAL, "antiparallel rings (neutral)"),
    ):
        loop = (eq.position[eq.converged] - ws.rest_position) / MM
        ax.plot(
            np.append(loop[:, 1], loop[:1, 1]),
            np.append(loop[:, 2], loop[:1, 2]),
            color=color,
            lw=1.5,
            label=label,
        )
    home = (ws.home.position - ws.rest_position)[1:] / MM
    ax.add_patch(
        Circle(
            tuple(home),
            ws.disc_radius / MM,
            fill=False,
            ls="--",
            color="k",
            label=f"largest disc about home, r = {ws.disc_radius / MM:.2f} mm",
        )
    )
    ax.plot(0, 0, "k+", ms=10, label="straight tip")
    ax.plot(*home, "kx", ms=8, label=f"home, droop {ws.droop / MM:.2f} mm")
    tip = ws.max_direction * ws.max_deflection / MM
    ax.annotate(
        "", xy=(tip[1], tip[2]), xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": "k"}
    )
    ax.text(tip[1], tip[2], f" max {ws.max_deflection / MM:.2f} mm", fontsize=8)
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
    d = (sweep.position - ws.rest_position) / MM
    t = np.rad2deg(sweep.command[:, 0])
    ax.plot(t, np.linalg.norm(d, axis=1), "k-", lw=2, label="|deflection|, theta2 = 0")
    ax.plot(t, d[:, 1], "-", color=REACH, label="y, theta2 = 0")
    ax.plot(t, d[:, 2], "-", color=NEUTRAL, label="z, theta2 = 0")
    dp = (ws.parallel.position - ws.rest_position) / MM
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


def plot_force_map(
    grid_deg: np.ndarray,
    force_mn: np.ndarray,
    path: Path,
    title: str,
    marks_deg: np.ndarray | None = None,
    mark_label: str = "",
) -> None:
    """The magnitude of the force the tip exerts on the obstacles [mN] over (theta1 rows,
    theta2 columns) [deg]; blank where the tip does not press; ``marks_deg`` (n, 2): ring
    angles marked on it (``steer --press``'s answers), labelled ``mark_label``."""
    fig, ax = plt.subplots(figsize=(6.0, 5.0))
    shown = np.ma.masked_invalid(force_mn.T)
    mesh = ax.pcolormesh(grid_deg, grid_deg, shown, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="force on the obstacle [mN]")
    if marks_deg is not None and len(marks_deg):
        ax.plot(*marks_deg.T, "o", ms=4, mfc="white", mec="crimson", label=mark_label)
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel("theta1 (distal ring) [deg]")
    ax.set_ylabel("theta2 (proximal ring) [deg]")
    ax.set_title(title + "\n(blank: no contact)", fontsize=9)
    ax.set_aspect("equal")
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
    path_states: Equilibria,
    others: list[Branch],
    load_factors: np.ndarray,
    title: str,
    path: Path,
) -> None:
    """A branch diagram: tip y, tip z and (with torsion) the rings' relative angle against
    the load factor; the state the robot reaches as its loads are brought up, snaps
    marked, beside the other branches (solid where stable, dashed where unstable)."""
    torsion = not np.allclose(path_states.tip_angles, path_states.command, equal_nan=True)
    panels = [
        ("tip y [mm]", lambda s: s.position[:, 1] / MM),
        ("tip z [mm]", lambda s: s.position[:, 2] / MM),
    ]
    if torsion:
        panels.append(
            (
                "theta1 - theta2 at the tip [deg]",
                lambda s: np.rad2deg(s.tip_angles[:, 0] - s.tip_angles[:, 1]),
            ),
        )
    # A quantity that stays zero on every branch (a set-up symmetric about the x-y
    # plane) says nothing: its panel is left out.
    panels = [
        p
        for p in panels
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
            for stable, style, name in (
                (True, "-", "other equilibria, stable"),
                (False, "--", "other equilibria, unstable"),
            ):
                part = np.where(branch.stable == stable, v, np.nan)
                ax.plot(load_factors, part, style, color="#888888", lw=1.2, label=label(name, part))
        v = value(path_states)
        ax.plot(load_factors, v, "-", color=REACH, lw=2.5, label=label("the state (load ramp)", v))
        snaps = np.flatnonzero(np.diff(path_states.snapped.astype(int)) > 0) + 1
        ax.plot(load_factors[snaps], v[snaps], "v", color=LOOP, ms=8, label=label("snap", v[snaps]))
        ax.set_xlabel("load factor (magnet brought up) [-]")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def plot_fronts(pareto: ParetoResult, best: OptimizationResult, study: Study, path: Path) -> None:
    """Objective against each swept bound, with the unconstrained optimum marked; points
    where the swept bound holds the design (:func:`binding`) filled, the others hollow."""
    sweeps = [(a, pts) for a, pts in pareto.sweeps.items() if pts]
    fig, axes = plt.subplots(1, len(sweeps), figsize=(5 * len(sweeps), 3.8), squeeze=False)
    best_objective = objective_in_report_units(study, best.objective)
    for ax, (against, pts) in zip(axes[0], sweeps, strict=True):
        unit, label = PARETO_UNITS[against]
        eps = np.array([p.epsilon for p in pts]) / unit
        obj = np.array([objective_in_report_units(study, p.objective) for p in pts])
        binds = np.array([binding(p, best.objective) for p in pts], dtype=bool)
        line_e, line_o = eps, obj
        if best.feasible:  # a bound the optimum meets leaves it the front's point
            line_e = np.r_[eps, best.metrics[against] / unit]
            line_o = np.r_[obj, best_objective]
        order = np.argsort(line_e)
        ax.plot(line_e[order], line_o[order], "-", color="tab:blue", lw=1)
        ax.plot(eps[binds], obj[binds], "o", color="tab:blue", label="bound binds")
        ax.plot(eps[~binds], obj[~binds], "o", mfc="white", color="tab:blue", label="bound slack")
        if best.feasible:
            ax.plot(
                best.metrics[against] / unit,
                best_objective,
                "r*",
                ms=14,
                label="optimum (no bound)",
            )
        ax.set_xlabel(label)
        ax.set_ylabel("disc radius [mm]" if len(study.objective) == 1 else "objective")
        ax.ticklabel_format(axis="y", useOffset=False)
        finite = np.r_[obj, best_objective]
        finite = finite[np.isfinite(finite)]
        if finite.size:
            ax.set_ylim(bottom=0, top=1.1 * finite.max())
        else:  # every point of this sweep infeasible: an empty panel that says so
            ax.text(0.5, 0.5, "no feasible point", transform=ax.transAxes, ha="center")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Pareto fronts of '{study.name}'")
    _save(fig, path, dpi=120)


def binding(point: ParetoPoint, optimum: float) -> bool:
    """Whether a Pareto point's swept bound holds its design: an active group of its NLP
    that costs objective, the point's objective more than 0.1 % below ``optimum`` (the
    unbounded study's, in the same units)."""
    r = point.result
    active = r is not None and r.feasible and f"epsilon.{point.against}" in r.active
    return bool(active and point.objective < optimum - 1e-3 * abs(optimum))


def plot_workspaces(start: Workspace, best: Workspace, path: Path, model: str = "") -> None:
    """Starting vs optimised reachable sets seen along x, from the straight tip, each with
    its parallel-ring loop, its home and its largest disc about home; ``model`` names the
    model in the title. [mm]"""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    for ws, colour, name in ((start, "tab:gray", "start"), (best, "tab:blue", "optimum")):
        pts = (ws.reachable - ws.rest_position) / MM
        ax.scatter(pts[:, 1], pts[:, 2], s=2, color=colour, alpha=0.4)
        loop = (ws.parallel.position - ws.rest_position) / MM
        ax.plot(loop[:, 1], loop[:, 2], "-", color=colour, lw=1.5, label=f"{name}: boundary")
        r = ws.disc_radius / MM
        home = (ws.home.position - ws.rest_position)[1:] / MM
        circle = Circle(
            tuple(home),
            r,
            fill=False,
            ls="--",
            color=colour,
            label=f"{name}: disc about home r = {r:.2f} mm",
        )
        ax.add_patch(circle)
        ax.plot(*home, "x", color=colour, ms=8, label=f"{name}: home")
    ax.plot(0, 0, "k+", ms=10, label="straight tip")
    ax.set_aspect("equal")
    ax.set_xlabel("y - y_straight [mm]")
    ax.set_ylabel("z - z_straight [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title("Workspace seen along x" + (f"\n{model} model" if model else ""), fontsize=10)
    _save(fig, path, dpi=110)


def plot_tip_views(start: Workspace, best: Workspace, path: Path, model: str) -> None:
    """Top (x-y) and side (x-z) views of the reachable tips of the start and the optimum,
    zoomed on the tips (axes not to scale: the cloud is far narrower in x); the rest tip
    marked; ``model`` named in the title. Base frame [mm]."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    clouds = [(best, "tab:blue", "optimum"), (start, "tab:orange", "start")]
    every = np.vstack([ws.reachable for ws, _, _ in clouds]) / MM
    for ax, j, view in ((axes[0], 1, "top view (x-y)"), (axes[1], 2, "side view (x-z)")):
        for ws, colour, name in clouds:
            pts = ws.reachable / MM
            ax.scatter(pts[:, 0], pts[:, j], s=3, color=colour, alpha=0.5, label=f"{name}: tips")
        rest = best.rest_position / MM
        ax.plot(rest[0], rest[j], "k+", ms=12, label="rest tip")
        lo, hi = every.min(axis=0), every.max(axis=0)
        pad = 0.08 * (hi - lo) + 0.5
        ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
        ax.set_ylim(lo[j] - pad[j], hi[j] + pad[j])
        ax.set_xlabel("x [mm]")
        ax.set_ylabel(f"{'xyz'[j]} [mm]")
        ax.set_title(view, fontsize=10)
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8)
    title = f"Reachable tips, {model} model (zoomed on the tips; axes not to scale)"
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    _save(fig, path, dpi=110)


def plot_tolerance(radii_mm: np.ndarray, nominal_mm: float, path: Path) -> None:
    """Histogram of the Monte Carlo samples' disc radius, the nominal design's marked. [mm]"""
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.hist(radii_mm, bins=20, color="tab:blue", alpha=0.8)
    ax.axvline(nominal_mm, color="r", label="nominal")
    ax.set_xlabel("disc radius [mm]")
    ax.set_ylabel("samples")
    ax.legend()
    ax.set_title("Tolerance Monte Carlo")
    _save(fig, path, dpi=110)


def _acquisition_rank(m: Measurements) -> np.ndarray:
    """Each row's place in the acquisition order (0 first)."""
    rank = np.empty(len(m))
    rank[m.order()] = np.arange(len(m))
    return rank


def compared_fits(d: Diagnosis) -> list[tuple[Fit, str, str]]:
    """The fits a diagnosis' plots show, with colour and legend label: the baseline and
    the final model; once where the final model is the baseline."""
    if d.final.calibration is d.baseline.calibration:
        return [(d.final, "tab:blue", "baseline (final)")]
    name = "baseline, refitted" if d.final.name == "baseline" else d.final.name
    return [(d.baseline, "tab:red", "baseline"), (d.final, "tab:blue", f"{name} (final)")]


def plot_residuals(d: Diagnosis, m: Measurements, path: Path) -> None:
    """Error per row [mm] against order, theta1 and theta1 - theta2, baseline vs final."""
    t1 = np.rad2deg(m.command[:, 0])
    diff = np.rad2deg((m.command[:, 0] - m.command[:, 1] + np.pi) % (2 * np.pi) - np.pi)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), sharey=True)
    for ax, x, label in zip(
        axes,
        (_acquisition_rank(m), t1, diff),
        ("acquisition order", "theta1 commanded [deg]", "theta1 - theta2 [deg]"),
        strict=True,
    ):
        for fit, colour, name in compared_fits(d):
            ax.plot(x, fit.calibration.errors / MM, "o", ms=3.5, color=colour, label=name)
        ax.set_xlabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("tip error [mm]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Calibrated model against the measurements, per row")
    _save(fig, path, dpi=110)


def plot_positions(d: Diagnosis, m: Measurements, path: Path) -> None:
    """Measured tips and both models' tips seen along x (the y-z plane, where the robot
    steers) [mm], each measurement joined to its predictions; for top views (no z), y
    against the acquisition order."""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    meas = m.position / MM
    has_z = np.isfinite(meas[:, 2]).mean() > 0.5
    order = _acquisition_rank(m)
    for fit, colour, name in compared_fits(d):
        model = (m.position - fit.calibration.residuals) / MM
        if has_z:
            a, b = model[:, 1], model[:, 2]
            segments_x = np.vstack([meas[:, 1], a, np.full(len(m), np.nan)]).T.ravel()
            segments_y = np.vstack([meas[:, 2], b, np.full(len(m), np.nan)]).T.ravel()
            ax.plot(segments_x, segments_y, "-", color=colour, lw=0.8, alpha=0.6)
        else:
            a, b = order, model[:, 1]
        ax.plot(a, b, "x", ms=5, color=colour, label=name)
    if has_z:
        ax.plot(meas[:, 1], meas[:, 2], "k.", ms=6, label="measured")
        ax.set_xlabel("y [mm]")
        ax.set_ylabel("z [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        title = "Tip positions seen along x (base frame), measured to model"
    else:
        ax.plot(order, meas[:, 1], "k.", ms=6, label="measured")
        ax.set_xlabel("acquisition order")
        ax.set_ylabel("y [mm]")
        title = "Tip y (top view data), measured and model"
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    _save(fig, path, dpi=110)

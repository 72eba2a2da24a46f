"""CSV tables of simulated tip poses (columns named as in spec/formats.md)."""

from __future__ import annotations

import csv
import io
import os

import numpy as np

from design.atomic import write_text
from design.equilibrium import Equilibria

POSE_COLUMNS = (
    "theta1_deg",
    "theta2_deg",
    "theta1_tip_deg",
    "theta2_tip_deg",
    "x_mm",
    "y_mm",
    "z_mm",
    "tangent_x",
    "tangent_y",
    "tangent_z",
    "deflection_mm",
    "converged",
    "stable",
    "snapped",
    "multistable",
    "failure",
)


def pose_rows(eq: Equilibria, rest: np.ndarray) -> list[dict]:
    """One row per configuration: commanded and tip ring angles [deg], tip [mm], tangent,
    deflection from ``rest`` [mm], flags, and why a row has no state (empty pose cells)."""
    rows = []
    commanded_deg = np.rad2deg(eq.command)
    tip_deg = np.rad2deg(eq.tip_angles)
    deflection = np.linalg.norm(eq.position - rest, axis=1) * 1e3
    for k in range(len(eq)):
        p, t = eq.position[k] * 1e3, eq.tangent[k]
        rows.append(
            {
                "theta1_deg": float(commanded_deg[k, 0]),
                "theta2_deg": float(commanded_deg[k, 1]),
                "theta1_tip_deg": tip_deg[k, 0],
                "theta2_tip_deg": tip_deg[k, 1],
                "x_mm": p[0],
                "y_mm": p[1],
                "z_mm": p[2],
                "tangent_x": t[0],
                "tangent_y": t[1],
                "tangent_z": t[2],
                "deflection_mm": deflection[k],
                "converged": bool(eq.converged[k]),
                "stable": bool(eq.stable[k]),
                "snapped": bool(eq.snapped[k]),
                "multistable": bool(eq.multistable[k]),
                "failure": str(eq.failure[k]),
            }
        )
    return rows


def write_csv(
    path: str | os.PathLike[str], rows: list[dict], columns: tuple[str, ...], header: str = ""
) -> None:
    """Write rows atomically; floats with 9 significant digits, NaN as an empty cell."""
    buf = io.StringIO()
    for line in header.splitlines():
        buf.write(f"# {line}\n")
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _cell(row[k]) for k in columns})
    write_text(path, buf.getvalue())


def _cell(value: object) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float | np.floating):
        return "" if not np.isfinite(value) else f"{float(value):.9g}"
    return str(value)

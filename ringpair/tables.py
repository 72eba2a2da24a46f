"""Tables of results and their CSV files: simulated tip poses (columns named as in
docs/formats.md), the model effects compared, the Pareto points, fitted estimates; and the
study report's tables (every dimension with its bounds, results per material, what each
limit costs, the CAD checks to show). File units (mm, deg, MPa)."""

from __future__ import annotations

import csv
import io
import math
import os
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from design.atomic import atomic_path, write_text
from design.contact import Contact
from design.equilibrium import Equilibria, solve_design
from design.geometry import rest_position
from design.model import RingPairModel, available_effects
from design.records import Design
from design.registry import PARAMETERS, file_unit
from design.stiffness import TipStiffness
from design.units import MM, MM3
from optimize.sizing.limit_costs import limit_meaning

if TYPE_CHECKING:
    from optimize.sizing.nlp import OptimizationResult
    from optimize.sizing.pareto import ParetoPoint, ParetoResult
    from optimize.sizing.studyfile import Study

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
    "stiffness_min_mN_per_mm",
    "stiffness_max_mN_per_mm",
    "in_contact",
    "contact_x_mm",
    "contact_y_mm",
    "contact_z_mm",
    "contact_force_x_mN",
    "contact_force_y_mN",
    "contact_force_z_mN",
)


def pose_rows(
    eq: Equilibria,
    rest: np.ndarray,
    stiffness: TipStiffness | None = None,
    contact: Contact | None = None,
) -> list[dict]:
    """One row per configuration: commanded and tip ring angles [deg], tip [mm], tangent,
    deflection from ``rest`` [mm], flags, why a row has no state (empty pose cells), and
    the tip stiffness's smallest and largest finite principal values (N/m = mN/mm; empty
    without ``stiffness``); the contact with an obstacle: in_contact, the contact point [mm]
    and the force the tip exerts on the obstacle [mN] (0 without contact)."""
    rows = []
    nan = np.full(len(eq), np.nan)
    lowest = nan if stiffness is None else stiffness.lowest
    highest = nan if stiffness is None else stiffness.highest
    n = len(eq)
    touching = np.zeros(n, bool) if contact is None else contact.in_contact
    point = np.full((n, 3), np.nan) if contact is None else contact.point / MM
    pushed = np.zeros((n, 3)) if contact is None else contact.force * 1e3 + 0.0  # (no -0)
    commanded_deg = np.rad2deg(eq.command)
    tip_deg = np.rad2deg(eq.tip_angles)
    deflection = np.linalg.norm(eq.position - rest, axis=1) / MM
    for k in range(len(eq)):
        p = eq.position[k] / MM
        posed = bool(np.isfinite(p).all())  # a row without a pose never claims a state
        t = eq.tangent[k] if posed else np.full(3, np.nan)
        tip = tip_deg[k] if posed else np.full(2, np.nan)
        rows.append(
            {
                "theta1_deg": float(commanded_deg[k, 0]),
                "theta2_deg": float(commanded_deg[k, 1]),
                "theta1_tip_deg": tip[0],
                "theta2_tip_deg": tip[1],
                "x_mm": p[0],
                "y_mm": p[1],
                "z_mm": p[2],
                "tangent_x": t[0],
                "tangent_y": t[1],
                "tangent_z": t[2],
                "deflection_mm": deflection[k],
                "converged": bool(eq.converged[k]) and posed,
                "stable": bool(eq.stable[k]) and posed,
                "snapped": bool(eq.snapped[k]),
                "multistable": bool(eq.multistable[k]),
                "failure": str(eq.failure[k]) or ("" if posed else "no finite pose"),
                "stiffness_min_mN_per_mm": float(lowest[k]),
                "stiffness_max_mN_per_mm": float(highest[k]),
                "in_contact": bool(touching[k]),
                "contact_x_mm": float(point[k, 0]),
                "contact_y_mm": float(point[k, 1]),
                "contact_z_mm": float(point[k, 2]),
                "contact_force_x_mN": float(pushed[k, 0]),
                "contact_force_y_mN": float(pushed[k, 1]),
                "contact_force_z_mN": float(pushed[k, 2]),
            }
        )
    return rows


def write_csv(
    path: str | os.PathLike[str], rows: list[dict], columns: tuple[str, ...], header: str = ""
) -> None:
    """Write rows atomically under ``header`` (as # lines); floats with 9 significant
    digits, NaN as an empty cell, booleans as true/false."""
    with csv_writer(path, columns, header) as put:
        put(rows)


@contextmanager
def csv_writer(
    path: str | os.PathLike[str], columns: tuple[str, ...], header: str = ""
) -> Iterator[Callable[[list[dict]], None]]:
    """:func:`write_csv` in batches: yields ``put(rows)``, which appends rows; the file
    appears (atomically) when the block ends, and not at all if it raises."""
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8", newline="") as f:
        for line in header.splitlines():
            f.write(f"# {line}\n")
        writer = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        yield lambda rows: writer.writerows({k: _cell(row[k]) for k in columns} for row in rows)


def _cell(value: object) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float | np.floating):
        return "" if not np.isfinite(value) else f"{float(value):.9g}"
    return str(value)


def estimate_text(value: float, error: float) -> str:
    """A fitted ``value`` written to the precision its one-sigma ``error`` gives it: one
    digit past the error's first (a tip mass at its bound of 0 g with a 0.03 g error
    shows 0.000, not the optimiser's 4.3e-10); 5 significant digits where the error is
    zero, unknown or infinite. Same units for both."""
    if not (math.isfinite(value) and math.isfinite(error) and error > 0):
        return f"{value:.5g}"
    decimals = max(0, 1 - math.floor(math.log10(error)))
    text = f"{value:.{decimals}f}"
    return text.lstrip("-") if float(text) == 0 else text


def effect_shifts(
    design: Design, theta1: np.ndarray, theta2: np.ndarray
) -> tuple[list[dict[str, str | float | int]], float]:
    """How far each model effect moves the tip of ``design`` against the paper's baseline.

    The rings are driven in order through every pair of ``theta1`` and ``theta2`` [rad]
    (theta2 varying fastest) with the baseline, with each effect on its own and with all of
    them. Returns one row per effect and the baseline's largest deflection [mm]. A row:
    ``max_shift_mm`` and ``rms_shift_mm``, the tip against the baseline's [mm];
    ``max_deflection_mm``, from the straight tip [mm]; ``without_state`` and ``snaps``,
    counts of configurations. Configurations without a state (NaN tip, under either model)
    are skipped by the largest and RMS values (nanmax, nanmean), not propagated as NaN.
    """
    g1, g2 = (g.ravel() for g in np.meshgrid(theta1, theta2, indexing="ij"))
    rest = rest_position(design.robot.free_length)
    base = solve_design(design, g1, g2, RingPairModel(), ordered=True)
    rows: list[dict[str, str | float | int]] = []
    for name in (*available_effects(), "all"):
        chosen = frozenset(available_effects()) if name == "all" else frozenset({name})
        eq = solve_design(design, g1, g2, RingPairModel(chosen), ordered=True)
        shift = np.linalg.norm(eq.position - base.position, axis=1) / MM
        rows.append(
            {
                "effect": name,
                "max_shift_mm": float(np.nanmax(shift)),
                "rms_shift_mm": float(np.sqrt(np.nanmean(shift**2))),
                "max_deflection_mm": _largest_deflection_mm(eq, rest),
                "without_state": int(np.count_nonzero(~eq.stable)),
                "snaps": int(np.count_nonzero(eq.snapped)),
            }
        )
    return rows, _largest_deflection_mm(base, rest)


def _largest_deflection_mm(eq: Equilibria, rest: np.ndarray) -> float:
    return float(np.nanmax(np.linalg.norm(eq.position - rest, axis=1)) / MM)


PARETO_UNITS = {
    "catheter_outer_diameter": (MM, "catheter outer diameter [mm]"),
    "external_distance": (MM, "external-magnet distance [mm]"),
    "magnet_volume": (MM3, "magnet volume, both rings [mm^3]"),
}
"""Swept Pareto quantity -> (its unit in SI, axis label): divide an SI value by the unit."""


def objective_in_report_units(study: Study, value: float) -> float:
    """The study's objective in report units (mm for the disc radius; as is otherwise)."""
    single = len(study.objective) == 1 and study.objective[0][0] == "disc_radius"
    return value / MM if single else value


def pareto_rows(points: tuple[ParetoPoint, ...], study: Study) -> list[dict[str, object]]:
    """One CSV row per Pareto point, in file units."""
    unit, _ = PARETO_UNITS[points[0].against] if points else (1.0, "")
    rows = []
    for p in points:
        r = p.result
        row: dict[str, object] = {
            "epsilon": p.epsilon / unit,
            "feasible": p.feasible,
            "objective": objective_in_report_units(study, p.objective),
            "active": ";".join(r.active) if r is not None else "",
            "error": p.error,
        }
        if r is not None and r.feasible:
            row |= _file_units(r.values)
        rows.append(row)
    return rows


def _file_units(values: dict[str, float]) -> dict[str, float]:
    """Free design values (by name, SI) under their study-file keys, in file units."""
    from optimize.sizing.studyfile import FREE_KEYS

    spec = {k.name: k for k in FREE_KEYS.values()}
    return {spec[k].key: v / spec[k].scale for k, v in values.items()}


def pareto_header(against: str, study: Study) -> str:
    """What a Pareto CSV's columns mean and their units, for its # lines."""
    from optimize.sizing.studyfile import PARETO_QUANTITIES

    _, label = PARETO_UNITS[against]
    sense = "at most" if PARETO_QUANTITIES[against][2] == "max" else "at least"
    single = len(study.objective) == 1
    objective = (
        "disc radius [mm]"
        if single and study.objective[0][0] == "disc_radius"
        else (f"{study.objective[0][0]} [SI]" if single else "weighted objective [-]")
    )
    return (
        f"Pareto sweep of study '{study.name}': one design NLP per row, {label} {sense} "
        "epsilon, the objective maximised.\n"
        f"epsilon: the bound, {label}; objective: {objective}; feasible: whether the NLP "
        "found a design; active: the constraints and bounds that hold it (';'-separated); "
        "error: why a point failed; the other columns: the free quantities, in the study "
        "file's units (as the key names say)."
    )


def write_pareto_csvs(pareto: ParetoResult, study: Study, folder: Path) -> list[Path]:
    """``pareto_<quantity>.csv`` in ``folder`` for each sweep of a ParetoResult (file
    units, # lines saying what each column means); the paths."""
    paths = []
    for against, points in pareto.sweeps.items():
        path = folder / f"pareto_{against}.csv"
        write_rows(path, pareto_rows(points, study), pareto_header(against, study))
        paths.append(path)
    return paths


def write_rows(
    path: str | os.PathLike[str], rows: list[dict[str, object]], header: str = ""
) -> None:
    """Write rows atomically as they are (Python's str of each cell), every key a column,
    under ``header`` (as # lines)."""
    _write(path, rows, list(dict.fromkeys(k for r in rows for k in r)), header)


def _write(
    path: str | os.PathLike[str], rows: list[dict], columns: Sequence[str], header: str = ""
) -> None:
    buf = io.StringIO()
    for line in header.splitlines():
        buf.write(f"# {line}\n")
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text(path, buf.getvalue())


# ------------------------------------------------------------ the study report's tables

TIGHT = 0.1
"""A passing CAD check whose value is within this fraction of its limit is shown expanded
with the failures (the others are collapsed)."""


MATERIAL_SET = ("youngs_modulus", "poisson_ratio", "density")
"""Properties of a tube that a study's material choice sets."""


def design_rows(study: Study, best: OptimizationResult) -> list[dict[str, Any]]:
    """Every dimension of the design, start and optimum, with the study's bounds for the
    free ones (file units): quantity, key, unit, start, optimum, low, high (None where not
    free), set_by ('free', 'fixed', or 'catheter material'/'wire material' where the
    study's material choice sets it), changed. The external magnet's distance is the rest
    tip to the magnet's centre."""
    assert best.design is not None
    rows = []
    for name, p in PARAMETERS.items():
        if p.field is None or p.key is None:
            continue
        unit, scale = file_unit(name)
        start, end = p.value(study.base) / scale, p.value(best.design) / scale
        b = study.bound(name)
        tube, _, what = name.partition("_")
        chosen = study.catheter_materials if tube == "catheter" else study.wire_materials
        by_material = what in MATERIAL_SET and bool(chosen)
        rows.append(
            {
                "quantity": p.meaning,
                "set_by": "free" if b else (f"{tube} material" if by_material else "fixed"),
                "key": p.key + (f"[{p.field[-2]}]" if p.field.endswith("]") else ""),
                "unit": unit,
                "start": start,
                "optimum": end,
                "low": b.low / scale if b else None,
                "high": b.high / scale if b else None,
                "changed": not np.isclose(start, end, rtol=1e-9, atol=NEGLIGIBLE),  # as printed
            }
        )
    b = study.bound("external_distance")
    start_d, end_d = best.base_metrics["external_distance"], best.metrics["external_distance"]
    rows.append(
        {
            "quantity": "external magnet distance, rest tip to the magnet's centre",
            "set_by": "free" if b else "fixed",
            "key": "external_distance_mm (study file)",
            "unit": "mm",
            "start": start_d / MM,
            "optimum": end_d / MM,
            "low": b.low / MM if b else None,
            "high": b.high / MM if b else None,
            "changed": not np.isclose(start_d, end_d, rtol=1e-9),
        }
    )
    return rows


def material_rows(study: Study, best: OptimizationResult) -> list[dict[str, Any]]:
    """Per material combination: the best accepted objective over its starts (report
    units; NaN when no start was accepted), starts accepted and tried."""
    out: dict[tuple, dict[str, Any]] = {}
    for s in best.starts:
        row = out.setdefault(
            s.materials,
            {
                "catheter": s.materials[0] or "as in the base design",
                "wire": s.materials[1] or "as in the base design",
                "objective": np.nan,
                "accepted": 0,
                "starts": 0,
            },
        )
        row["starts"] += 1
        if s.accepted:
            row["accepted"] += 1
            value = objective_in_report_units(study, s.objective)
            row["objective"] = np.nanmax([row["objective"], value])
    return list(out.values())


def limit_rows(best: OptimizationResult, moved: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The sensitivity stage's rows ``moved`` (:func:`ringpair.pipeline.sensitivity`), then
    the active items of ``best`` it could not move (a bound at the end of what its quantity
    admits, as a gap at 0 mm, or a limit the study does not set), without a gain (NaN) and
    with the ``reason``."""
    rows = list(moved)
    covered = {g for r in rows for g in r["groups"]}
    for item in best.active:
        if item not in covered and not item.startswith("epsilon."):
            rows.append(
                {
                    "meaning": limit_meaning(item),
                    "reason": "not moved: "
                    + (
                        "at the end of what the quantity admits"
                        if item.startswith("bound.")
                        else "the study sets no limit for it"
                    ),
                    "limit": item,
                    "groups": [item],
                    "unit": "",
                    "old": np.nan,
                    "new": np.nan,
                    "multiplier": np.nan,
                    "objective": np.nan,
                    "gain": np.nan,
                }
            )
    return rows


def check_rows(checks: list[dict[str, Any]]) -> tuple[list[dict], list[dict]]:
    """The CAD checks split in those to show (failed, or passing within TIGHT of a
    numeric limit ``>= x``/``<= x``) and the rest."""
    shown: list[dict[str, Any]] = []
    rest: list[dict[str, Any]] = []
    for c in checks:
        m = re.match(r"\s*(>=|<=|>|<)\s*(-?[0-9.eE+-]+)", str(c.get("limit", "")))
        tight = False
        if m and isinstance(c.get("value"), int | float | np.floating):
            limit = float(m.group(2))
            margin = (
                float(c["value"]) - limit if m.group(1)[0] == ">" else limit - float(c["value"])
            )
            tight = margin < TIGHT * max(abs(limit), 1e-9)
        (shown if tight or not c.get("passed", True) else rest).append(c)
    return shown, rest


NEGLIGIBLE = 1e-6
"""A design quantity below this in its file unit (mm, MPa, deg, T, ...) is printed as 0: an
optimiser's rounding (a 5e-11 mm gap), not a number anyone can make."""


def page_number(value: Any, digits: int = 4) -> str:
    """A number in file units for the page: ``digits`` significant digits, never an
    exponent; 0 below NEGLIGIBLE, whole numbers with thousands grouped from 10,000 (a NiTi
    modulus 60,000 MPa, not 6e+04); empty where it is not a finite number."""
    if value is None or not math.isfinite(float(value)):
        return ""
    v = float(value)
    if abs(v) < NEGLIGIBLE:
        return "0"
    if abs(v) >= 1e4:
        return f"{v:,.0f}"
    return np.format_float_positional(v, precision=digits, unique=False, fractional=False, trim="-")


CHECK_DECIMALS = {"mm": 3, "deg": 2}
"""Decimals a CAD check's value is shown with, by unit: a micrometre, a hundredth of a
degree (the checks' own tolerances are coarser)."""


def check_value_text(value: Any, unit: str) -> str:
    """A CAD check's value for the page, without raw exponents: lengths to the micrometre,
    angles to 0.01 deg, relative differences and fractions in percent, counts as integers;
    a value that is not a finite number says so."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if not isinstance(value, int | float | np.floating) or not math.isfinite(float(value)):
        return "not measured"
    v = float(value)
    if unit in CHECK_DECIMALS:
        return f"{v:.{CHECK_DECIMALS[unit]}f}"
    if unit in ("relative", "fraction"):
        return f"{100 * v:.2f} %"
    if v == round(v):
        return str(int(round(v)))
    return f"{v:.4f}"

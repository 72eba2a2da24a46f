"""The study's ``results.json``: every number the report shows, in file units, with the
notes on the Pareto fronts (:func:`results`); the page is :mod:`ringpair.report_html`."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from design.units import MM, MM3
from ringpair.parts_report import model_title
from ringpair.pipeline import Run, forward_model
from ringpair.plots import (
    binding,
)
from ringpair.report_notes import rounding_note
from ringpair.tables import (
    PARETO_UNITS,
    design_rows,
    limit_rows,
    material_rows,
    objective_in_report_units,
)


def model_names(run: Run) -> tuple[str, str]:
    """The study's model and the model for design work, as a reader names them
    (:func:`ringpair.parts_report.model_title`)."""
    return model_title(run.study.effects), model_title(forward_model(run.study).effects)


def front_notes(run: Run) -> dict[str, str]:
    """One sentence per Pareto sweep: what the front means and where its bound binds."""
    from optimize.sizing.studyfile import PARETO_QUANTITIES

    best, study = run.results["optimise"], run.study
    opt = objective_in_report_units(study, best.objective)
    notes = {}
    for against, pts in run.results.get("pareto", _NoSweeps).sweeps.items():
        if not pts:
            continue
        unit, label = PARETO_UNITS[against]
        name, u = re.match(r"(.*) \[(.*)\]", label).groups()  # type: ignore[union-attr]
        name = name.replace(", ", " (", 1) + ")" if ", " in name else name
        sense = "at most" if PARETO_QUANTITIES[against][2] == "max" else "at least"
        eps = np.array([p.epsilon for p in pts]) / unit
        obj = np.array([objective_in_report_units(study, p.objective) for p in pts])
        binds = np.array([binding(p, best.objective) for p in pts], dtype=bool)
        mine = best.metrics[against] / unit
        text = (
            f"The best disc radius when the {name} must be {sense} a bound, swept from "
            f"{eps.min():.3g} to {eps.max():.3g} {u} (the optimum has {mine:.3g} {u}). "
        )
        if not binds.any():
            text += (
                f"Flat at {np.nanmax(obj):.2f} mm: the bound does not bind in this range, "
                f"every bound swept already admits the optimum's {mine:.3g} {u}"
                + (", which sits at its own bound in the study" if _at_bound(best, against) else "")
                + "."
            )
        else:
            e, o = eps[binds], obj[binds]
            worst = int(np.nanargmin(o))
            slope = (opt - o[worst]) / max(abs(mine - e[worst]), 1e-12)
            text += (
                (
                    f"It binds at {e[0]:.3g} {u}"
                    if len(e) == 1
                    else f"It binds from {e.min():.3g} to {e.max():.3g} {u}"
                )
                + f": at {e[worst]:.3g} {u} the disc radius is {o[worst]:.2f} mm, "
                f"{opt - o[worst]:.2f} mm below the optimum's, about {slope:.2g} mm of disc "
                f"radius per {u} the bound is tightened past the optimum's {mine:.3g} {u}."
            )
        failed = int(np.count_nonzero(~np.array([p.feasible for p in pts])))
        if failed:
            text += f" {failed} of {len(pts)} points found no design."
        notes[against] = text
    return notes


class _NoSweeps:
    sweeps: dict = {}


def _at_bound(best: Any, against: str) -> bool:
    return any(a.startswith(f"bound.{against}.") for a in best.active)


def number_text(x: Any, fmt: str = ".3g") -> str:
    return "" if x is None or not np.isfinite(x) else format(x, fmt)


def results(run: Run) -> dict[str, Any]:
    """Every number of the report, in report units (mm, mm^3, deg)."""
    best = run.results["optimise"]
    fwd = run.results["forward"]
    tol = run.results["tolerance"]["disc_radius"] / MM
    start_ws, best_ws = fwd["start"], fwd["best"]
    study_model, work_model = model_names(run)

    def metrics(m: dict[str, float]) -> dict[str, float]:
        return {
            "disc_radius_mm": m["disc_radius"] / MM,
            "reach_ratio": m["reach_ratio"],
            "neutral_deflection_mm": m["neutral_deflection"] / MM,
            "magnet_volume_mm3": m["magnet_volume"] / MM3,
            "external_distance_to_centre_mm": m["external_distance"] / MM,
        }

    from optimize.sizing.nlp_problem import GROUPS

    constraints = {
        c.name: {
            "meaning": GROUPS[c.name][2] if c.name in GROUPS else "",
            "value": c.value / c.scale,
            "limit": c.limit / c.scale,
            "unit": c.unit,
            "active": c.active,
            "multiplier": c.multiplier,
        }
        for c in best.constraints
    }
    doc: dict[str, Any] = {
        "study": run.study.name,
        "model": study_model,
        "start": metrics(best.base_metrics),
        "best": metrics(best.metrics),
        "materials": list(best.materials),
        "per_material": material_rows(run.study, best),
        "design": design_rows(run.study, best),
        "constraints": constraints,
        "active": list(best.active),
        "limits": limit_rows(best, run.results.get("sensitivity", [])),
        "pareto": front_notes(run),
        "forward": {"model": work_model}
        | _forward_numbers("start", start_ws, fwd["start_controllable"])
        | _forward_numbers("best", best_ws, fwd["best_controllable"])
        | _torsion_numbers(fwd.get("best_torsion"))
        | {
            "unrounded_disc_radius_mm": fwd["optimum"].disc_radius / MM
            if "optimum" in fwd
            else None,
            "rounding": rounding_note(fwd),
        },
        "tolerance": {
            "samples": int(len(tol)),
            "disc_radius_mean_mm": float(np.mean(tol)),
            "disc_radius_std_mm": float(np.std(tol)),
            "disc_radius_p05_mm": float(np.percentile(tol, 5)),
            "disc_radius_p95_mm": float(np.percentile(tol, 95)),
        },
        "effects": run.results["effects"],
        "cad": {
            "passed": run.results["cad"]["passed"],
            "checks": len(run.results["cad"]["checks"]),
        },
        "timings_s": run.seconds,
        "warnings": [
            "disc_radius_mm is the disc about the robot's home (rings antiparallel, in the "
            "model) that it can be steered over without a snap (issue 49); before, the disc "
            "about the straight tip, now forward.*_straight_disc_radius_mm",
            "forward.*_controllable_disc_radius_mm are deprecated: they equal "
            "forward.*_disc_radius_mm",
        ],
    }
    if "diagnosis" in run.results:
        doc["diagnosis"] = run.results["diagnosis"]
    return doc


def _forward_numbers(which: str, ws: Any, ctl: Any) -> dict[str, Any]:
    """One design's forward numbers: the disc (about home, steerable without a snap), the
    home's droop, the reach beyond home, the straight-tip disc, the controllable share;
    ``controllable_disc_radius_mm``, the old name of the disc, kept (equal). [mm]"""
    return {
        f"{which}_disc_radius_mm": ctl.disc_radius / MM,
        f"{which}_controllable_disc_radius_mm": ctl.disc_radius / MM,
        f"{which}_droop_mm": ws.droop / MM,
        f"{which}_home_mm": [float(v) / MM for v in ws.home.position],
        f"{which}_reach_mm": dict(
            zip(("+y", "-y", "+z", "-z"), (r / MM for r in ws.reach), strict=True)
        ),
        f"{which}_straight_disc_radius_mm": ws.straight_disc_radius / MM,
        f"{which}_controllable_fraction": ctl.fraction,
    }


def _torsion_numbers(t: dict[str, Any] | None) -> dict[str, Any]:
    """The recommended design with torsion added to the model for design work (what that
    model leaves out), in report units; empty where the model has torsion. [mm]"""
    if t is None:
        return {}
    return {
        "best_torsion": {
            "effects": t["effects"],
            "disc_radius_mm": t["disc_radius"] / MM,
            "workspace_disc_radius_mm": t["workspace_disc_radius"] / MM,
            "droop_mm": t["droop"] / MM,
            "home_stable": t["home_stable"],
            "controllable_fraction": t["controllable_fraction"],
            "snapped": t["snapped"],
            "configurations": t["configurations"],
            "seconds": t["seconds"],
        }
    }

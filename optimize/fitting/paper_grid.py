"""The paper's calibration, kept as a named baseline method: an exhaustive grid over a
stiffness scale K_E and a field scale K_B (Sayres & Pittiglio, Model Tuning: K_E in
[0.009, 0.018], K_B in [3.5, 4.5], minimising the largest tip error; they found
K_E = 0.009, K_B = 4.03). SI units are used for all inputs and outputs; the ``*_mm``
figures are millimetres.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from design.model import model_for
from design.records import Design
from design.registry import index
from design.units import MM
from optimize.fitting.measurements import Measurements
from optimize.fitting.sensitivity import position_errors, predict

PAPER_STIFFNESS_GRID = np.linspace(2 / 3, 4 / 3, 10)
"""The paper's K_E grid, 0.009 .. 0.018 in steps of 0.001 (10 values), relative to its
centre 0.0135: a factor of 2 in 10 steps. Multiplied by ``stiffness_center``."""
PAPER_FIELD_GRID = np.linspace(0.875, 1.125, 101)
"""The paper's K_B grid, 3.5 .. 4.5 in steps of 0.01 (101 values), relative to its centre
4.0: +-12.5 % in steps of 0.25 %. Multiplied by ``field_center``."""


@dataclass(frozen=True)
class GridResult:
    """The paper's two-factor exhaustive search.

    stiffness_scale, field_scale : the best grid point (K_E, K_B). [-]
    objective : shape (len(stiffness_grid), len(field_grid)), the criterion at every grid
        point (the paper's: largest distance); NaN where a configuration did not solve. [m]
    params : shape (n,), model parameters at the best point. [SI]
    errors : shape (N,), distances at the best point. [m]
    rmse_mm, max_abs_mm : of ``errors``. [mm]
    evaluations : model solves (one per grid point); time_s : wall time. [s]
    """

    stiffness_scale: float
    field_scale: float
    stiffness_grid: np.ndarray
    field_grid: np.ndarray
    objective: np.ndarray
    params: np.ndarray
    errors: np.ndarray
    rmse_mm: float
    max_abs_mm: float
    evaluations: int
    time_s: float


def paper_pulls(design: Design, stiffness: float, field_scale: float) -> dict[str, float]:
    """What the paper's factors K_E, K_B (:func:`two_factor_parameters`) ask of the
    physical parameters, as pulls against the default priors
    (:mod:`optimize.fitting.calibrate.priors`): the bending rigidity scaled by K_E, the
    external remanence by K_B, and the external magnet's centre moved to K_B times its
    place (by name; prior sigmas, signed). [-]"""
    from design.registry import PARAMETERS

    out = {
        "bending_rigidity_scale": math.log(stiffness) / _width("bending_rigidity_scale"),
        "external_remanence": math.log(field_scale) / _width("external_remanence"),
    }
    magnet = design.external_magnet
    assert magnet is not None, "the paper's K_B scales the external magnet"
    for a, centre in zip("xyz", magnet.center, strict=True):
        spec = PARAMETERS[f"external_center_{a}"].fit
        assert spec is not None
        out[f"external_center_{a}"] = (field_scale - 1) * centre / spec.step / spec.prior
    return out


def _width(name: str) -> float:
    from design.registry import PARAMETERS

    spec = PARAMETERS[name].fit
    assert spec is not None
    return spec.prior


def two_factor_parameters(base: np.ndarray, stiffness: float, field_scale: float) -> np.ndarray:
    """The paper's parameterisation: K_E scales the bending rigidity; K_B scales the
    external dipole's moment and its position (m_e' = K_B m_e, p_e' = K_B p_e, the
    paper's eq. for the tuned field). [SI]"""
    p = base.copy()
    p[index("bending_rigidity_scale")] *= stiffness
    p[index("external_remanence")] *= field_scale
    for a in "xyz":
        p[index(f"external_center_{a}")] *= field_scale
    return p


def grid_search_two_factors(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    *,
    stiffness_grid: np.ndarray | None = None,
    field_grid: np.ndarray | None = None,
    stiffness_center: float = 1.0,
    field_center: float = 1.0,
    objective: str = "max",
    ordered: bool | None = None,
) -> GridResult:
    """The paper's calibration: an exhaustive search over a stiffness scale K_E and a
    field scale K_B (:func:`two_factor_parameters`) minimising the largest tip error
    (``objective='max'``, the paper's e_max) or the RMS error (``'rms'``). Default grid:
    the paper's resolution (PAPER_STIFFNESS_GRID x PAPER_FIELD_GRID, 10 x 101 points)
    around the given centres. Each grid point solves every configuration once."""
    if objective not in ("max", "rms"):
        raise ValueError(f"objective must be 'max' or 'rms'; got {objective!r}")
    t0 = time.perf_counter()
    model = model_for(frozenset(effects))
    base = model.parameters(design)
    ks = stiffness_center * (PAPER_STIFFNESS_GRID if stiffness_grid is None else stiffness_grid)
    kb = field_center * (PAPER_FIELD_GRID if field_grid is None else field_grid)
    table = np.full((len(ks), len(kb)), np.nan)
    best: tuple[float, int, int, np.ndarray] = (np.inf, 0, 0, np.full(len(m), np.nan))
    for i, ke in enumerate(ks):
        for j, kf in enumerate(kb):
            p = two_factor_parameters(base, ke, kf)
            e = position_errors(predict(model, p, m, ordered).equilibria.position, m)
            if not np.isfinite(e).all():
                continue
            value = float(e.max() if objective == "max" else np.sqrt(np.mean(e**2)))
            table[i, j] = value
            if value < best[0]:
                best = (value, i, j, e)
    _, i, j, e = best
    ok = np.isfinite(e)
    return GridResult(
        stiffness_scale=float(ks[i]),
        field_scale=float(kb[j]),
        stiffness_grid=ks,
        field_grid=kb,
        objective=table,
        params=two_factor_parameters(base, ks[i], kb[j]),
        errors=e,
        rmse_mm=float(np.sqrt(np.mean(e[ok] ** 2)) / MM) if ok.any() else float("nan"),
        max_abs_mm=float(e[ok].max() / MM) if ok.any() else float("nan"),
        evaluations=table.size,
        time_s=time.perf_counter() - t0,
    )

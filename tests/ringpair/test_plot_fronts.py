"""The Pareto-front figure of a study whose every point is infeasible (it crashed with
"Axis limits cannot be NaN" before)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from PIL import Image

from optimize.sizing.pareto import ParetoPoint, ParetoResult
from optimize.sizing.studyfile import default_study
from ringpair.plots import plot_fronts


def test_fronts_of_a_study_with_no_feasible_point_draw_an_empty_panel(tmp_path):
    points = tuple(
        ParetoPoint("external_distance", eps, None, error="IPOPT: infeasible")
        for eps in (0.2, 0.25, 0.3)
    )
    pareto = ParetoResult(
        {"external_distance": points}, solved=3, resumed=0, seconds=1.0, workers=1
    )
    best = SimpleNamespace(objective=float("nan"), feasible=False, metrics={})
    path = tmp_path / "fronts.png"
    plot_fronts(pareto, best, default_study(), path)
    pixels = np.asarray(Image.open(path).convert("L"))
    assert pixels.shape[0] > 100 and (pixels < 128).any()  # a drawn figure, not blank

"""Ellipse fit and distances (design.ellipse), against ellipses made up with known
parameters: points on a drawn ellipse give it back (Fitzgibbon, Pilu & Fisher 1999 fit an
ellipse exactly through points on one); points moved along the ellipse's normal by a known
amount are that far from it (the closest point of a smooth curve lies along the normal, for
offsets below the smallest radius of curvature). The seed of each case is in its test id."""

from __future__ import annotations

import numpy as np
import pytest

from design.ellipse import Ellipse, fit_ellipse


def _drawn(rng) -> Ellipse:
    a = rng.uniform(0.5, 40.0)
    return Ellipse(
        center=rng.uniform(-50.0, 50.0, 2),
        semi_axes=np.array([a, a * rng.uniform(0.2, 1.0)]),
        angle=rng.uniform(-np.pi / 2, np.pi / 2),
    )


@pytest.mark.parametrize("seed", range(9000, 9020))
def test_points_on_a_drawn_ellipse_give_it_back(seed):
    rng = np.random.default_rng(seed)
    truth = _drawn(rng)
    points = truth.point(rng.uniform(0, 2 * np.pi, int(rng.integers(5, 60))))
    fitted = fit_ellipse(points)
    scale = truth.semi_axes[0]
    np.testing.assert_allclose(fitted.center, truth.center, atol=1e-7 * scale, err_msg=str(seed))
    np.testing.assert_allclose(fitted.semi_axes, truth.semi_axes, rtol=1e-7, err_msg=str(seed))
    # The same ellipse: every point of one is on the other.
    assert fitted.distance(truth.point(np.linspace(0, 6, 50))).max() < 1e-7 * scale, seed


@pytest.mark.parametrize("seed", range(9100, 9120))
def test_points_moved_along_the_normal_are_that_far(seed):
    rng = np.random.default_rng(seed)
    e = _drawn(rng)
    t = rng.uniform(0, 2 * np.pi, 40)
    a, b = e.semi_axes
    # Smallest radius of curvature b^2 / a: offsets below it keep the normal's foot closest.
    offset = rng.uniform(-0.9, 0.9, 40) * b * b / a
    c, s = np.cos(e.angle), np.sin(e.angle)
    normal = np.column_stack([b * np.cos(t), a * np.sin(t)])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    normal = np.column_stack(
        [c * normal[:, 0] - s * normal[:, 1], s * normal[:, 0] + c * normal[:, 1]]
    )
    points = e.point(t) + offset[:, None] * normal
    np.testing.assert_allclose(e.distance(points), np.abs(offset), atol=1e-9 * a, err_msg=str(seed))


def test_fit_refuses_too_few_points():
    with pytest.raises(ValueError, match="at least 5"):
        fit_ellipse(np.zeros((4, 2)))

"""Renders are real pictures: the parts cover the image, the magnet halves show."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from cad.build import CadReport


def _image(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


def _part_fraction(img: np.ndarray) -> float:
    """Share of pixels that differ from the background gradient (which varies by row
    only; column 0 is background in every picture)."""
    background = img[:, :1, :]
    diff = np.abs(img - background).max(axis=2)
    body = img[60:]  # below the title line
    return float(np.mean(diff[60:] > 25.0)) if body.size else 0.0


@pytest.mark.parametrize(
    "name",
    [
        "assembly.png",
        "actuator.png",
        "exploded.png",
        "tip.png",
        "tip_section.png",
        "parts/worm.png",
        "parts/gear_shaft_front.png",
        "parts/mounting_piece_proximal.png",
        "parts/housing.png",
    ],
)
def test_render_shows_the_part(fdm_build: CadReport, name: str) -> None:
    path = fdm_build.out_dir / "renders" / name
    img = _image(path)
    assert img.shape[0] >= 800 and img.shape[1] >= 1000
    assert _part_fraction(img) > 0.03


def test_every_printed_part_has_a_picture(fdm_build: CadReport) -> None:
    for part in fdm_build.parts:
        path = fdm_build.out_dir / "renders" / "parts" / f"{part['name']}.png"
        assert path.exists() == (part["printed"] or part["name"] == "ring_magnet")


def test_section_shows_both_poles_of_the_rings(fdm_build: CadReport) -> None:
    img = _image(fdm_build.out_dir / "renders" / "tip_section.png")
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 150) & (g < 90) & (b < 90)
    blue = (b > 150) & (r < 90) & (g < 130)
    assert red.sum() > 100
    assert blue.sum() > 100

"""The resin process: finer fits give slimmer tip pieces, and everything still checks out."""

from __future__ import annotations

import pytest

from cad.build import CadReport, build_parts
from design.records import Design


@pytest.mark.slow
def test_resin_build_passes_every_check(
    demonstrator: Design, fdm_build: CadReport, tmp_path
) -> None:
    resin = build_parts(demonstrator, tmp_path, "resin", render=False)
    assert resin.failures == []
    assert not (tmp_path / "renders").exists()
    size = {p["name"]: p["size_mm"] for p in resin.parts}
    fdm_size = {p["name"]: p["size_mm"] for p in fdm_build.parts}
    # Resin: 0.05 mm fit, 0.5 mm walls -> a thinner tip than FDM (0.15 mm, 1 mm).
    assert size["mounting_piece_proximal"][0] < fdm_size["mounting_piece_proximal"][0] - 2.0
    walls = [r for r in resin.checks if r["check"] == "min_wall"]
    assert all("(resin)" in str(r["limit"]) for r in walls)
    # The same gears: the drive numbers do not depend on the process but the backlash.
    assert resin.drive["centre_distance_mm"] == pytest.approx(fdm_build.drive["centre_distance_mm"])
    assert resin.drive["backlash_mm"] < fdm_build.drive["backlash_mm"]

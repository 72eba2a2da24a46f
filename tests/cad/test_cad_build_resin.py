"""The resin process: the actuator's parts follow it, the tip pieces stay the design's (the
pieces the model carries, issue 48), and everything still checks out."""

from __future__ import annotations

import pytest

from cad.build import TIP_PIECES, CadReport, build_parts
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
    # The tip pieces are the design's in both builds; the actuator's fits are the process's.
    for piece in TIP_PIECES:
        assert size[piece] == pytest.approx(fdm_size[piece], abs=1e-9), piece
    volume = {p["name"]: p["volume_mm3"] for p in resin.parts}
    fdm_volume = {p["name"]: p["volume_mm3"] for p in fdm_build.parts}
    assert volume["shaft_bushing"] > fdm_volume["shaft_bushing"]  # 0.1 mm running fit, not 0.3
    walls = [r for r in resin.checks if r["check"] == "min_wall"]
    assert all("(resin)" in str(r["limit"]) for r in walls)
    # The same gears: the drive numbers do not depend on the process but the backlash.
    assert resin.drive["centre_distance_mm"] == pytest.approx(fdm_build.drive["centre_distance_mm"])
    assert resin.drive["backlash_mm"] < fdm_build.drive["backlash_mm"]

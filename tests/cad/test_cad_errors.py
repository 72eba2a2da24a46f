"""Impossible dimensions end with one clear message naming the quantity, expected, found."""

from __future__ import annotations

from dataclasses import replace

import pytest

from cad.build import build_parts
from cad.errors import CadError
from cad.layout import ActuatorSpec
from cad.mounting import MountingSpec, build_mounting_pieces
from cad.process import FDM, get_process
from cad.tracking import GrooveSpec
from design.records import Design


def test_cad_error_is_a_value_error() -> None:
    assert issubclass(CadError, ValueError)


def test_magnet_seat_larger_than_the_piece_is_rejected(demonstrator: Design) -> None:
    with pytest.raises(CadError) as err:
        build_mounting_pieces(demonstrator, FDM, MountingSpec(outer_diameter_mm=4.0))
    msg = str(err.value)
    assert "magnet seat diameter" in msg
    assert "outer diameter 4 mm" in msg
    assert "got 4.15 mm" in msg  # 4 mm magnet + 0.15 mm FDM fit allowance


def test_wire_bore_larger_than_the_magnet_bore_is_rejected(demonstrator: Design) -> None:
    wire = replace(demonstrator.robot.wire, outer_diameter=1.9e-3)
    design = replace(demonstrator, robot=replace(demonstrator.robot, wire=wire))
    with pytest.raises(CadError) as err:
        build_mounting_pieces(design, FDM)
    msg = str(err.value)
    assert "wire bore diameter" in msg
    assert "smaller than the magnet bore (tip.magnet_inner_diameter_mm = 2)" in msg
    assert "got 2.05 mm" in msg


def test_magnet_bore_without_running_clearance_on_the_wire_is_rejected(
    demonstrator: Design,
) -> None:
    # The demonstrator's wire is 0.4 mm; design.geometry.WIRE_CLEARANCE asks 0.05 mm more.
    tip = replace(demonstrator.tip, magnet_inner_diameter=0.42e-3)
    with pytest.raises(CadError) as err:
        build_mounting_pieces(replace(demonstrator, tip=tip), FDM)
    msg = str(err.value)
    assert "tip ring: magnet bore" in msg
    assert "at least the wire diameter (0.4 mm) plus 0.05 mm" in msg
    assert "got 0.42 mm" in msg


def test_catheter_too_wide_for_the_piece_is_rejected(demonstrator: Design) -> None:
    cath = replace(demonstrator.robot.catheter, outer_diameter=6e-3, inner_diameter=1.0e-3)
    design = replace(demonstrator, robot=replace(demonstrator.robot, catheter=cath))
    with pytest.raises(CadError, match=r"catheter socket diameter .* must be at most"):
        build_mounting_pieces(design, FDM, MountingSpec(outer_diameter_mm=9.45))


def test_groove_longer_than_its_pitch_is_rejected() -> None:
    with pytest.raises(CadError, match=r"groove travel must be at most one pitch .*got 50 mm"):
        GrooveSpec(pitch_mm=40.0, travel_mm=50.0)


def test_unknown_process_is_rejected() -> None:
    with pytest.raises(CadError, match=r"process must be one of 'fdm', 'resin'; got 'sls'"):
        get_process("sls")


def test_gear_shaft_too_thin_for_the_catheter_is_rejected(demonstrator: Design, tmp_path) -> None:
    with pytest.raises(CadError, match=r"catheter socket in the front shaft .* at most"):
        build_parts(demonstrator, tmp_path / "cad", actuator=ActuatorSpec(shaft_journal_mm=3.0))
    assert not (tmp_path / "cad").exists()


def test_a_rejected_build_writes_nothing(demonstrator: Design, tmp_path) -> None:
    out = tmp_path / "cad"
    with pytest.raises(CadError):
        build_parts(demonstrator, out, mounting=MountingSpec(outer_diameter_mm=4.0))
    assert not out.exists()

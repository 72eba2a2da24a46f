"""The parameter symbols of a model by name (:data:`design.registry.NAMES`, then the
field sources' parameters), with the derived quantities the model uses. SI units."""

from __future__ import annotations

import casadi as ca
import numpy as np

from design.fields.fieldmap import FieldMap
from design.fields.sources import KINDS, split_parameters
from design.geometry import magnet_spacing, ring_centres
from design.magnets import cylinder_moment, ring_moment, ring_volume
from design.model.field import CLASSIC, FieldLayout
from design.mounting import tip_geometry
from design.registry import NAMES
from design.sections import polar_moment_of_area, second_moment_of_area, shear_modulus


class Symbols(dict):
    """Parameter symbols by name, with the derived quantities the model uses; ``prm`` holds
    :data:`design.registry.NAMES`, then the parameters of ``layout``'s sources."""

    def __init__(self, prm: ca.SX, layout: FieldLayout = CLASSIC) -> None:
        n = len(NAMES)
        super().__init__(zip(NAMES, ca.vertsplit(prm[:n]), strict=True))
        s = self
        self.layout = layout
        self.sources: list[tuple[str, dict[str, ca.SX], FieldMap | None]] = []
        """Each source's kind, quantities (:func:`design.fields.sources.split_parameters`)
        and grid (a map's)."""
        start = n
        for kind, fieldmap in zip(layout.kinds, layout.maps, strict=True):
            size = sum(q.size for q in KINDS[kind])
            block = prm[start : start + size]
            self.sources.append((kind, split_parameters(kind, block), fieldmap))
            start += size
        tubes = {}
        for tube in ("catheter", "wire"):
            od, idia = s[f"{tube}_outer_diameter"], s[f"{tube}_inner_diameter"]
            e = s[f"{tube}_youngs_modulus"]
            tubes[tube] = {
                "EI": e * second_moment_of_area(od, idia),
                "GJ": shear_modulus(e, s[f"{tube}_poisson_ratio"]) * polar_moment_of_area(od, idia),
                "weight_per_length": s[f"{tube}_density"] * np.pi / 4 * (od**2 - idia**2),
            }
        self.bending_rigidity = s["bending_rigidity_scale"] * (
            tubes["catheter"]["EI"] + tubes["wire"]["EI"]
        )
        # Ring 1 (distal, theta1) is turned by the wire, ring 2 (proximal) by the catheter.
        self.torsional_rigidity = ca.vertcat(
            s["wire_torsion_scale"] * tubes["wire"]["GJ"],
            s["catheter_torsion_scale"] * tubes["catheter"]["GJ"],
        )
        self.rod_mass_per_length = (
            tubes["catheter"]["weight_per_length"] + tubes["wire"]["weight_per_length"]
        )
        od, idia, h = s["magnet_outer_diameter"], s["magnet_inner_diameter"], s["magnet_length"]
        self.ring_moment = ring_moment(od, idia, h, s["magnet_remanence"])
        self.ring_mass = s["magnet_density"] * ring_volume(od, idia, h)
        self.magnet_spacing = magnet_spacing(h, s["magnet_gap"])
        axis = ca.vertcat(*(s[f"external_magnetization_{a}"] for a in "xyz"))
        self.external_magnetization = axis / ca.norm_2(axis)
        self.external_center = ca.vertcat(
            s["external_center_x"], s["external_center_y"], s["external_center_z"]
        )
        self.external_moment = self.external_magnetization * cylinder_moment(
            s["external_diameter"], s["external_length"], s["external_remanence"]
        )
        self.gravity = ca.vertcat(s["gravity_x"], s["gravity_y"], s["gravity_z"])
        self.applied_force = ca.vertcat(*(s[f"applied_force_{a}"] for a in "xyz"))
        self.applied_moment = ca.vertcat(*(s[f"applied_moment_{a}"] for a in "xyz"))
        self.tip = tip_geometry(
            s["magnet_outer_diameter"], s["magnet_inner_diameter"], s["magnet_length"],
            s["magnet_gap"], s["catheter_outer_diameter"], s["wire_outer_diameter"],
            s["catheter_inner_diameter"], s["mount_wall"], s["mount_fit_allowance"],
            s["mount_running_clearance"], s["mount_density"], s["stop_angle"],
            passage_diameter=ca.if_else(
                s["mount_passage_diameter"] > 0,
                s["mount_passage_diameter"],
                s["catheter_inner_diameter"],
            ),
        )  # fmt: skip
        """The printed mounting pieces (:func:`design.mounting.tip_geometry`)."""
        self.rod_length = s["free_length"]
        """The flexible rod's length: the free length, less the rigid tip segment's offset
        where the model has ``printed_tip`` (it sets this). [m]"""


def ring_positions(s: Symbols, position: ca.SX, frame: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(proximal, distal) ring centres of the robot whose rod tip is at ``position`` (3,)
    with ``frame`` (3, 3), base frame (:func:`design.geometry.ring_centres`). [m]"""
    return ring_centres(position, frame[:, 0], s.magnet_spacing)

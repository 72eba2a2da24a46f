"""How wrong the point dipole is near the demonstrator's external magnet.

Prints the relative error of the point-dipole field (moment Br / mu0 * volume, the
baseline model) against the exact cylinder field (``design.cylinder_field``), for B and
for its gradient dB/dp (which sets the force), against the distance from the magnet's
centre in diameters, along the axis, at 45 degrees and across it (90 degrees); then the
same at the demonstrator's straight-robot tip. Far away the error falls like (a / r)^2;
on the axis it is (2 b^2 - 3 a^2 / 2) / z^2 + O(z^-4), i.e. -(a / z)^2 for this magnet
(length = radius).

    python benchmarks/dipole_error.py [--design path/to/design.toml]
"""

from __future__ import annotations

import argparse
import math

import casadi as ca
import numpy as np

from design.constants import MU0
from design.cylinder_field import cylinder_field
from design.designfile import default_design, load_design
from design.dipole import dipole_field, dipole_field_gradient
from design.geometry import rest_position

DISTANCES = (0.6, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0, 5.0, 10.0)  # [diameters from the centre]
ANGLES = (0.0, 45.0, 90.0)  # [deg from the magnetisation axis]


def error_function(magnet) -> ca.Function:
    """offset [m] -> (|B_dip - B| / |B|, ||G_dip - G|| / ||G||, |B|, ||G||, |B_dip| / |B|,
    ||G_dip|| / ||G||)."""
    offset = ca.SX.sym("offset", 3)
    axis = ca.DM(magnet.magnetization)
    moment = magnet.remanence / MU0 * math.pi * (magnet.diameter / 2) ** 2 * magnet.length
    flux, grad = cylinder_field(offset, axis, magnet.diameter / 2, magnet.length, magnet.remanence)
    flux_dip = dipole_field(offset, moment * axis)
    grad_dip = dipole_field_gradient(offset, moment * axis)
    return ca.Function(
        "dipole_error",
        [offset],
        [
            ca.norm_2(flux_dip - flux) / ca.norm_2(flux),
            ca.norm_fro(grad_dip - grad) / ca.norm_fro(grad),
            ca.norm_2(flux),
            ca.norm_fro(grad),
            ca.norm_2(flux_dip) / ca.norm_2(flux),
            ca.norm_fro(grad_dip) / ca.norm_fro(grad),
        ],
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", help="design file (default: the demonstrator)")
    args = ap.parse_args()
    design = load_design(args.design) if args.design else default_design()
    magnet = design.external_magnet
    errors = error_function(magnet)
    axis = np.asarray(magnet.magnetization, float)
    across = np.cross(axis, [0.0, 0.0, 1.0])
    if np.linalg.norm(across) < 1e-9:
        across = np.cross(axis, [0.0, 1.0, 0.0])
    across /= np.linalg.norm(across)

    print(
        f"external magnet: {magnet.diameter * 1e3:.1f} mm diameter x "
        f"{magnet.length * 1e3:.1f} mm, Br {magnet.remanence:.2f} T "
        f"(D = diameter; distances from the centre; the surface is at 0.25 D on the axis "
        f"and 0.5 D across it)"
    )
    header = "  r/D " + "".join(f" | B err {a:3.0f} deg  G err {a:3.0f} deg" for a in ANGLES)
    print(header)
    print("-" * len(header))
    for r in DISTANCES:
        row = f"{r:5.2f} "
        for angle in np.radians(ANGLES):
            direction = math.cos(angle) * axis + math.sin(angle) * across
            e_b, e_g, *_ = (float(v) for v in errors(r * magnet.diameter * direction))
            row += f" | {e_b:12.2%}  {e_g:12.2%}"
        print(row)

    tip = rest_position(design.robot.free_length)  # straight robot, base frame
    offset = tip - np.asarray(magnet.center)
    e_b, e_g, b_abs, g_abs, b_ratio, g_ratio = (float(v) for v in errors(offset))
    cos_angle = abs(offset @ axis) / np.linalg.norm(offset)
    print(
        f"\n{design.name} tip (straight robot) at {np.linalg.norm(offset) / magnet.diameter:.2f} D,"
        f" {math.degrees(math.acos(min(cos_angle, 1.0))):.0f} deg off the axis: |B| = "
        f"{b_abs * 1e3:.1f} mT, ||dB/dp|| = {g_abs:.3f} T/m; dipole error {e_b:.1%} in B, "
        f"{e_g:.1%} in the gradient (dipole / exact magnitude: {b_ratio:.3f} and {g_ratio:.3f})"
    )


if __name__ == "__main__":
    main()

"""An independent solve of the ring-pair robot's state, written separately from the
project's solver, for tests.

The same physics, written anew in numpy from the design record: the external field from
magpylib's cylinder (``near_field``) or a numpy point dipole, the force on a ring by
central differences of that field, the rings' mutual torque with the project's K12 (tested
on its own), gravity, and two rods:

- the linear cantilever (the paper's small-deflection model, the equations of
  design/cantilever.py): its equilibrium equations r(q) = q - C Q(q) - q_w (and the
  transmissions' twist) are followed along the flow x' = -r (downhill) as the loads are
  ramped from zero in small steps, a tracing of the quasi-static path;
- the large-deflection rod as a chain of N rigid links joined at their midpoints by
  bending springs EI / h, frames carried by the joints' rotations without twist (the
  discrete Kirchhoff rod with infinite torsional rigidity; the tip converges to the
  continuous rod's as 1 / (4 N^2)); its total potential energy is minimised (L-BFGS,
  analytic gradient) at each step of the same load ramp, starting from the last minimum,
  so that it follows the branch and, past a fold, goes downhill to the next minimum.

With the printed tip (``printed_tip``, the mounting pieces of :mod:`design.mounting`, whose
dimensions are read only through :func:`design.mounting.tip_geometry`) the flexible rod
(either kind) is shorter by the rigid segment's offset: it ends at the proximal piece's
proximal face, and a rigid body carries the rings, the tracked point (the proximal ring's
centre, ``rigid_offset`` along the rod's end tangent) and the pieces, whose weights act at
their centres of mass. Every load on that body is a point load (force at a point, couple)
whose moment about the rod's end is summed as such. With ``torsion`` the pieces' stops are
a contact on the rings' relative angle rho = theta1 - theta2 (tip), held within [0, S]: a
one-sided spring of the model's contact stiffness (``design.stops.STOP_STIFFNESS`` times
the two transmissions in series; a chosen number, not physics), potential
k/2 (min(rho, 0)^2 + max(rho - S, 0)^2); the wire's command is the relative command taken
within the turn centred on [0, S], plus the pre-twist (docs/formats.md). Without
``torsion`` the rings sit at their commanded angles and stops and pre-twist do not act.

Both start from the unloaded, straight robot with the rings at their commanded angles.
:func:`energy_hessian_eigenvalues` gives the finite-difference Hessian of the chain's
energy at a state (a stability check independent of the solver's). SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass

import magpylib as magpy
import numpy as np
from scipy.integrate import LSODA, solve_ivp
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from design.mounting import tip_geometry
from design.records import Design
from design.ring_coupling import coupling_coefficient
from design.stops import STOP_STIFFNESS

MU0 = 4e-7 * np.pi * 1.00000000055  # CODATA 2018 vacuum permeability [T m / A]
MAGPY_MU0 = magpy.mu_0
"""The vacuum permeability magpylib converts H to B with. [T m / A]"""
FD_STEP = 2e-6
"""Central-difference step of the field gradient. [m]"""


@dataclass(frozen=True)
class Robot:
    """What the oracle needs, computed from the design record. [SI]"""

    length: float  # free length: base to the tracked point; the transmissions twist over it
    rod: float  # the flexible rod: the free length less the rigid segment's offset
    offset: float  # rod's end to the tracked point (the proximal ring's centre) [m]
    ei: float
    gj: np.ndarray  # (wire -> distal ring, catheter -> proximal ring)
    mass_per_length: float
    moment: float  # of each ring
    spacing: float
    ring_mass: float
    tip_mass: float
    pieces: tuple[tuple[float, float], ...]  # (arm from the rod's end, mass) of each piece
    k12: float
    gravity: np.ndarray
    stops: tuple[float, float] | None  # (stop angle S, pre-twist) with the printed tip

    def ring_centres(self, end: np.ndarray, tangent: np.ndarray) -> np.ndarray:
        """(distal, proximal) ring centres (2, 3) of the rod's end at ``end`` with
        ``tangent``: on the rigid segment, the proximal one at the tracked point."""
        return np.vstack(
            [end + (self.offset + self.spacing) * tangent, end + self.offset * tangent]
        )

    def point_masses(self) -> tuple[np.ndarray, np.ndarray]:
        """(arms from the rod's end along its tangent (k,), masses (k,)) of everything the
        rod's end carries: the rings, the extra tip mass at the proximal ring's centre, the
        printed pieces at their centres of mass. [m, kg]"""
        arms = [self.offset + self.spacing, self.offset, self.offset]
        masses = [self.ring_mass, self.ring_mass, self.tip_mass]
        for arm, mass in self.pieces:
            arms.append(arm)
            masses.append(mass)
        return np.array(arms), np.array(masses)

    def commanded(self, command: np.ndarray) -> np.ndarray:
        """The angles the twisting transmissions (``torsion``) are turned to (2,): the
        command, or with stops the wire's relative command within the turn centred on
        [0, S] plus the pre-twist. (Rigid in torsion, the transmissions hold the rings at
        the command, and stops and pre-twist do not act: docs/formats.md.)"""
        if self.stops is None:
            return np.asarray(command, float)
        stop, pretwist = self.stops
        relative = command[0] - command[1]
        centred = stop / 2 + np.mod(relative - stop / 2 + np.pi, 2 * np.pi) - np.pi
        return np.array([command[1] + centred + pretwist, command[1]])

    def stop_contact(self, angles: np.ndarray) -> tuple[float, float]:
        """(potential [J], its derivative in rho [N m]) of the stops at tip angles
        ``angles``; zero without stops."""
        if self.stops is None:
            return 0.0, 0.0
        k = STOP_STIFFNESS / (self.length / self.gj[0] + self.length / self.gj[1])
        rho = angles[0] - angles[1]
        below, above = min(rho, 0.0), max(rho - self.stops[0], 0.0)
        return 0.5 * k * (below**2 + above**2), k * (below + above)


def robot(design: Design, printed: bool = False) -> Robot:
    """The oracle's robot; ``printed``: with the printed tip (``printed_tip``)."""
    r, t = design.robot, design.tip

    def section(tube):
        i = np.pi * (tube.outer_diameter**4 - tube.inner_diameter**4) / 64
        g = tube.youngs_modulus / (2 * (1 + tube.poisson_ratio))
        area = np.pi * (tube.outer_diameter**2 - tube.inner_diameter**2) / 4
        return tube.youngs_modulus * i, g * 2 * i, tube.density * area

    ei_c, gj_c, mu_c = section(r.catheter)
    ei_w, gj_w, mu_w = section(r.wire)
    volume = np.pi * (t.magnet_outer_diameter**2 - t.magnet_inner_diameter**2) / 4
    volume *= t.magnet_length
    spacing = t.magnet_length + t.magnet_gap
    k12 = coupling_coefficient(
        t.magnet_outer_diameter,
        t.magnet_inner_diameter,
        t.magnet_length,
        spacing,
        t.magnet_remanence,
    )
    g = design.environment.gravity
    offset, pieces, stops = 0.0, (), None
    if printed:
        m = t.mounting
        geometry = tip_geometry(
            t.magnet_outer_diameter, t.magnet_inner_diameter, t.magnet_length, t.magnet_gap,
            r.catheter.outer_diameter, r.wire.outer_diameter, r.catheter.inner_diameter,
            m.wall, m.fit_allowance, m.running_clearance, m.density, m.stop_angle,
        )  # fmt: skip
        offset = float(geometry.rigid_offset)
        pieces = (
            (float(geometry.proximal_arm), float(geometry.proximal_mass)),
            (float(geometry.distal_arm), float(geometry.distal_mass)),
        )
        stops = (m.stop_angle, m.pretwist)
    return Robot(
        length=r.free_length,
        rod=r.free_length - offset,
        offset=offset,
        ei=ei_c + ei_w,
        gj=np.array([gj_w, gj_c]),
        mass_per_length=mu_c + mu_w,
        moment=t.magnet_remanence / MU0 * volume,
        spacing=spacing,
        ring_mass=t.density * volume,
        tip_mass=t.mass,
        pieces=pieces,
        k12=k12,
        gravity=np.zeros(3) if g is None else np.asarray(g, float),
        stops=stops,
    )


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


class Field:
    """B at points (k, 3) of the design's field: the external magnet (magpylib's cylinder,
    or its dipole) and the field sources (magpylib's cuboid, sphere, axial-cylinder and
    current-loop kernels, or for a permanent magnet without ``near_field`` its numpy
    dipole; a uniform field), superposed (field maps are not modelled here).

    The kernels are magpylib's own (``magpylib.core``: the functions its ``Cuboid``,
    ``Sphere``, ``Cylinder`` and ``Circle`` objects evaluate), called once per source on
    all points, each in its source's frame (a cylinder's and a coil's axis, a cuboid's
    sides along the base axes): an object's ``getB`` costs ~1.5 ms of input checks per
    call, which made the oracle's flows minutes long. :meth:`objects` gives the objects,
    and the tests check that both agree."""

    def __init__(self, design: Design, near: bool) -> None:
        self.near = near
        self.magnets: list[tuple[np.ndarray, np.ndarray]] = []  # (centre, moment) dipoles
        self.cylinders: list[tuple] = []  # (centre, axis, radius, half length, remanence)
        self.cuboids: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # centre, sides, J
        self.spheres: list[tuple[np.ndarray, float, np.ndarray]] = []  # centre, diameter, J
        self.coils: list[tuple[np.ndarray, np.ndarray, float, float]] = []  # c, axis, r, NI
        self.uniform = np.zeros(3)
        e = design.external_magnet
        if e is not None:
            axis = _unit(e.magnetization)
            volume = np.pi * e.diameter**2 / 4 * e.length
            if near:
                self.cylinders.append((np.asarray(e.center, float), axis, e.diameter / 2,
                                       e.length / 2, e.remanence))  # fmt: skip
            else:
                self.magnets.append(
                    (np.asarray(e.center, float), e.remanence / MU0 * volume * axis)
                )
        for src in design.sources:
            self._add(src)

    def _add(self, src) -> None:
        centre = np.asarray(src.center, float)
        mag = np.asarray(src.magnetization, float)
        if src.kind == "uniform":
            self.uniform = self.uniform + np.asarray(src.b, float)
        elif src.kind == "coil":
            self.coils.append((centre, _unit(src.axis), src.radius, src.turns * src.current))
        elif src.kind == "sphere":  # (exactly its dipole outside, near_field or not)
            self.spheres.append((centre, src.diameter, src.remanence * mag))
        elif src.kind == "cuboid" and self.near:
            self.cuboids.append((centre, np.asarray(src.dimensions, float), src.remanence * mag))
        elif src.kind == "cylinder" and self.near:
            self.cylinders.append((centre, _unit(mag), src.diameter / 2, src.length / 2,
                                   src.remanence))  # fmt: skip
        elif src.kind in ("cuboid", "cylinder"):
            if src.kind == "cuboid":
                volume = float(np.prod(src.dimensions))
            else:
                volume = np.pi * src.diameter**2 / 4 * src.length
            self.magnets.append((centre, src.remanence / MU0 * volume * mag))
        else:
            raise ValueError(f"the oracle has no {src.kind} source")

    def __call__(self, points: np.ndarray) -> np.ndarray:
        points = np.atleast_2d(points)
        k = len(points)
        out = np.zeros_like(points, dtype=float) + self.uniform
        for centre, axis, radius, half, remanence in self.cylinders:  # Derby & Olbert 2010
            d = points - centre
            z = d @ axis
            radial = d - z[:, None] * axis
            rho = np.linalg.norm(radial, axis=1)
            b_rho, _, b_z = magpy.core.magnet_cylinder_axial_Bfield(
                np.full(k, half / radius), rho / radius, z / radius
            )
            unit = radial / np.where(rho > 0, rho, 1.0)[:, None]
            out = out + remanence * (b_rho[:, None] * unit + b_z[:, None] * axis)
        for centre, sides, pol in self.cuboids:
            out = out + magpy.core.magnet_cuboid_Bfield(
                points - centre, np.tile(sides, (k, 1)), np.tile(pol, (k, 1))
            )
        for centre, diameter, pol in self.spheres:
            out = out + magpy.core.magnet_sphere_Bfield(
                points - centre, np.full(k, diameter), np.tile(pol, (k, 1))
            )
        for centre, axis, radius, current in self.coils:
            d = points - centre
            z = d @ axis
            radial = d - z[:, None] * axis
            rho = np.linalg.norm(radial, axis=1)
            h_rho, _, h_z = magpy.core.current_circle_Hfield(
                np.full(k, radius), rho, z, np.full(k, current)
            )
            unit = radial / np.where(rho > 0, rho, 1.0)[:, None]
            out = out + MAGPY_MU0 * (h_rho[:, None] * unit + h_z[:, None] * axis)
        for centre, moment in self.magnets:
            d = points - centre
            r = np.linalg.norm(d, axis=1)[:, None]
            out = out + MU0 / (4 * np.pi) * (3 * d * (d @ moment)[:, None] / r**5 - moment / r**3)
        return out

    def objects(self) -> list:
        """magpylib's objects of the sources that :meth:`__call__` evaluates by their
        kernels (the cylinders, cuboids, spheres and coils), posed by magpylib."""
        out: list = []
        for centre, axis, radius, half, remanence in self.cylinders:
            rot, _ = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])
            out.append(magpy.magnet.Cylinder(
                polarization=(0, 0, remanence), dimension=(2 * radius, 2 * half),
                position=centre, orientation=rot,
            ))  # fmt: skip
        for centre, sides, pol in self.cuboids:
            out.append(magpy.magnet.Cuboid(polarization=pol, dimension=sides, position=centre))
        for centre, diameter, pol in self.spheres:
            out.append(magpy.magnet.Sphere(polarization=pol, diameter=diameter, position=centre))
        for centre, axis, radius, current in self.coils:
            rot, _ = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])
            out.append(magpy.current.Circle(
                current=current, diameter=2 * radius, position=centre, orientation=rot
            ))  # fmt: skip
        return out

    def with_gradient(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """B (k, 3) and dB/dp (k, 3, 3), [i, j] = dB_i / dp_j, by central differences."""
        steps = FD_STEP * np.vstack([np.eye(3), -np.eye(3)])
        allp = np.vstack([points] + [points + s for s in steps])
        b = self(allp).reshape(7, len(points), 3)
        grad = (b[1:4] - b[4:7]).transpose(1, 2, 0) / (2 * FD_STEP)
        return b[0], grad


def ring_clearance(design: Design, tip: np.ndarray, tangent: np.ndarray) -> float:
    """The smaller distance of the two rings' bounding spheres (about the rod tip and one
    spacing along the tangent) to the external magnet's solid cylinder; negative inside
    it. [m]"""
    e, t = design.external_magnet, design.tip
    if e is None:
        return np.inf  # (the sources' magnets: the design file keeps them off the robot)
    axis = np.asarray(e.magnetization, float)
    axis = axis / np.linalg.norm(axis)
    reach = np.hypot(t.magnet_outer_diameter / 2, t.magnet_length / 2)
    out = np.inf
    for centre in (tip, tip + (t.magnet_length + t.magnet_gap) * tangent):
        d = centre - np.asarray(e.center, float)
        along = d @ axis
        across = np.linalg.norm(d - along * axis)
        beyond = np.hypot(max(abs(along) - e.length / 2, 0.0), max(across - e.diameter / 2, 0.0))
        out = min(out, beyond - reach)
    return float(out)


def _frame_from_rotation_vector(phi: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(phi).as_matrix()


def ring_moments(frame: np.ndarray, angles: np.ndarray, moment: float) -> np.ndarray:
    """Moments (2, 3) of the distal and proximal rings turned by ``angles`` in the tip
    frame (columns tangent, y, z)."""
    return moment * (np.cos(angles)[:, None] * frame[:, 1] + np.sin(angles)[:, None] * frame[:, 2])


# ---------------------------------------------------------------------------- linear rod


def _linear_residual(
    x: np.ndarray,
    command: np.ndarray,
    rb: Robot,
    field: Field,
    lam: float,
    torsion: bool,
    gravity: bool,
) -> np.ndarray:
    """The paper's linear cantilever (of the flexible rod's length) and the transmissions'
    twist, written anew. The rod's end sits at (rod, q0, q1) with the frame of the rotation
    vector (0, q2, q3); what it carries loads it through the force sum and the moment
    about the end."""
    L, ei = rb.rod, rb.ei
    q = x[:4]
    angles = x[4:6] if torsion else command
    frame = _frame_from_rotation_vector(np.array([0.0, q[2], q[3]]))
    tangent = frame[:, 0]
    end = np.array([L, q[0], q[1]])
    centres = rb.ring_centres(end, tangent)  # distal, proximal
    moments = lam * ring_moments(frame, angles, rb.moment)
    b, grad = field.with_gradient(centres)
    forces = np.einsum("kij,ki->kj", grad, moments)  # grad(m . B)
    torques = np.cross(moments, b)
    force = forces.sum(axis=0)
    torque = torques.sum(axis=0) + np.cross(centres - end, forces).sum(axis=0)
    w = np.zeros(3)
    if gravity:
        g = lam * rb.gravity
        arms, masses = rb.point_masses()
        force = force + masses.sum() * g
        torque = torque + np.cross((arms * masses).sum() * tangent, g)
        w = rb.mass_per_length * g
    bending = torque - (torque @ tangent) * tangent
    a, bb, c = L**3 / (3 * ei), L**2 / (2 * ei), L / ei
    loaded = np.array(
        [
            a * force[1] + bb * bending[2],
            a * force[2] - bb * bending[1],
            -bb * force[2] + c * bending[1],
            bb * force[1] + c * bending[2],
        ]
    )
    weight = np.array(
        [
            L**4 / (8 * ei) * w[1],
            L**4 / (8 * ei) * w[2],
            -(L**3) / (6 * ei) * w[2],
            L**3 / (6 * ei) * w[1],
        ]
    )
    r = q - loaded - weight
    if not torsion:
        return r
    axial = np.einsum("ki,i->k", torques, tangent)
    coupling = lam**2 * rb.k12 * np.sin(angles[0] - angles[1])
    contact = -rb.stop_contact(angles)[1]  # the stops' torque on the distal ring
    axial = axial + np.array([coupling + contact, -coupling - contact])
    return np.concatenate([r, angles - rb.commanded(command) - rb.length / rb.gj * axial])


def _jacobian(fun, x: np.ndarray, step: float = 1e-7) -> np.ndarray:
    """Central-difference Jacobian of ``fun`` at x."""
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = step
        cols.append((fun(x + e) - fun(x - e)) / (2 * step))
    return np.column_stack(cols)


REST = 1e-9
"""The flow rests where its largest component is below this ([m] of the rod's end, [rad];
the residual's own finite-difference noise is ~1e-9)."""


def _flow_to_rest(solver: LSODA, touching) -> tuple[np.ndarray, str]:
    """Step ``solver`` (the flow, from its start) until the flow is below :data:`REST` at
    a step's end ('rested'), the rings touch a magnet there (``touching`` (y) [m] <= 0:
    'touching'), or the solver fails ('lost') or reaches its end ('lost', unless the flow
    is below 1e-7 there: 'rested'). Returns (the state there, status). The steps are LSODA's (those
    of ``solve_ivp``); where the flow comes to rest within a step is not located (a root
    search in the step's interpolant cost ~40 evaluations of the field per event, and
    failed where the event changed sign twice within a step)."""
    while True:
        solver.step()
        y = solver.y
        if touching(y) <= 0:
            return y, "touching"
        size = np.abs(solver.fun(solver.t, y)).max()
        if size <= REST:
            return y, "rested"
        if solver.status == "failed":
            return y, "lost"
        if solver.status == "finished":
            return y, "rested" if size <= 1e-7 else "lost"


def linear_state(
    design: Design,
    effects: frozenset[str],
    command: np.ndarray,
    ramp: int = 20,
    tolerance: float = 1e-12,
) -> tuple[np.ndarray, np.ndarray, float]:
    """The linear rod's state at ``command`` (2,) [rad]: the flow x' = -r followed with
    error control (scipy's LSODA, which switches to implicit BDF steps where the flow is
    stiff, so the trajectory is the flow's and does not jump to another equilibrium; Radau
    stalled on some flows) at each step of the load ramp until
    the residual is below :data:`REST`, then polished by Newton at full load. r = C grad V
    with C the compliance (symmetric positive definite), so the flow goes downhill of the
    potential V and rests only in a minimum, where the real robot comes to rest. Returns
    (unknowns (4 or 6,), tip position (3,), the smallest :func:`ring_clearance` at the
    states of the ramp [m]); NaN if the flow is lost."""
    rb = robot(design, "printed_tip" in effects)
    field = Field(design, "near_field" in effects)
    torsion, gravity = "torsion" in effects, "gravity" in effects
    x = np.zeros(6 if torsion else 4)
    if torsion:
        x[4:] = rb.commanded(command)
    nan = np.full_like(x, np.nan), np.full(3, np.nan), np.nan
    clearance = np.inf

    def tangent_of(y):
        return _frame_from_rotation_vector(np.array([0.0, y[2], y[3]]))[:, 0]

    def tip_of(y):  # the tracked point
        return np.array([rb.rod, y[0], y[1]]) + rb.offset * tangent_of(y)

    # From load 0: with stops the unloaded robot first settles against them.
    for lam in np.linspace(0.0, 1.0, ramp + 1):

        def flow(_t, y, lam=lam):
            return -_linear_residual(y, command, rb, field, lam, torsion, gravity)

        def touching(y):
            return ring_clearance(design, tip_of(y), tangent_of(y))

        if np.abs(flow(0.0, x)).max() > REST:
            atol = 1e-10 * np.where(np.arange(x.size) < 2, rb.length, 1.0)  # [m], [rad]
            x, status = _flow_to_rest(LSODA(flow, 0.0, x, 1e6, rtol=1e-6, atol=atol), touching)
            clearance = min(clearance, touching(x))
            if status == "touching":  # the rings reached the magnet (contact: the end)
                return nan[0], nan[1], min(clearance, 0.0)
            if status != "rested":  # failed, or never came to rest
                return nan[0], nan[1], clearance
    for _ in range(20):
        r = -flow(0.0, x)
        if np.abs(r).max() < tolerance:
            break
        x = x - np.linalg.solve(-_jacobian(lambda y: flow(0.0, y), x), r)
    return x, tip_of(x), min(clearance, ring_clearance(design, tip_of(x), tangent_of(x)))


def linear_stiffness_eigenvalues(
    design: Design, effects: frozenset[str], command: np.ndarray, x: np.ndarray
) -> np.ndarray:
    """Eigenvalues of the symmetric part of K_s dr/dx at x (K_s: the cantilever's stiffness
    and the transmissions' GJ / L; dr/dx by central differences), each scaled by its
    diagonal: the Hessian of the total potential of the linear model (conservative to
    first order), so all positive iff stable."""
    rb = robot(design, "printed_tip" in effects)
    field = Field(design, "near_field" in effects)
    torsion, gravity = "torsion" in effects, "gravity" in effects
    L, ei = rb.rod, rb.ei
    k = np.array(
        [
            [12 * ei / L**3, 0, 0, -6 * ei / L**2],
            [0, 12 * ei / L**3, 6 * ei / L**2, 0],
            [0, 6 * ei / L**2, 4 * ei / L, 0],
            [-6 * ei / L**2, 0, 0, 4 * ei / L],
        ]
    )
    if torsion:
        k = np.block([[k, np.zeros((4, 2))], [np.zeros((2, 4)), np.diag(rb.gj / rb.length)]])
    jac = _jacobian(lambda y: _linear_residual(y, command, rb, field, 1.0, torsion, gravity), x)
    h = k @ jac
    h = 0.5 * (h + h.T)
    d = 1 / np.sqrt(np.abs(np.diag(h)))
    return np.linalg.eigvalsh(h * np.outer(d, d))


# ---------------------------------------------------------------------------- chain rod


def _exp(w: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) of rotation vectors (N, 3)."""
    return Rotation.from_rotvec(w).as_matrix()


def _right_jacobian(w: np.ndarray) -> np.ndarray:
    """Right Jacobians (N, 3, 3) of SO(3): d Exp(w) = Exp(w) [J_r(w) dw]^."""
    theta = np.linalg.norm(w, axis=1)
    k = np.zeros((len(w), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    small = theta < 1e-6
    t = np.where(small, 1.0, theta)
    a = np.where(small, 0.5 - theta**2 / 24, (1 - np.cos(t)) / t**2)
    b = np.where(small, 1 / 6 - theta**2 / 120, (t - np.sin(t)) / t**3)
    return np.eye(3) - a[:, None, None] * k + b[:, None, None] * (k @ k)


class Chain:
    """The large-deflection rod as N links (see the module docstring); unknowns: the
    joints' rotation vectors (y, z components in the link frame), then the tip ring angles
    with torsion. With the printed tip the links span the flexible rod only and the last
    link's frame carries the rigid segment."""

    def __init__(self, design: Design, effects: frozenset[str], links: int = 100) -> None:
        self.rb = robot(design, "printed_tip" in effects)
        self.field = Field(design, "near_field" in effects)
        self.torsion = "torsion" in effects
        self.gravity = "gravity" in effects
        self.n = links
        self.h = self.rb.rod / links

    def _shape(self, w2: np.ndarray):
        """(joint rotation vectors, frames (n + 1), joints, the rod's end)."""
        n, h = self.n, self.h
        w = np.zeros((n, 3))
        w[:, 1:] = w2.reshape(n, 2)
        rot = _exp(w)
        frames = np.empty((n + 1, 3, 3))
        frames[0] = np.eye(3)
        for k in range(n):
            frames[k + 1] = frames[k] @ rot[k]
        tangents = frames[:, :, 0]
        joints = np.empty((n, 3))
        joints[0] = [h / 2, 0.0, 0.0]
        joints[1:] = joints[0] + h * np.cumsum(tangents[1:n], axis=0)
        end = joints[-1] + h / 2 * tangents[n]
        return w, frames, joints, end

    def _masses(self, joints: np.ndarray, end: np.ndarray, tangent: np.ndarray):
        """Point masses (k,) at positions (k, 3) of the rod links (beyond the clamp's half
        link) and of everything the rod's end carries (:meth:`Robot.point_masses`), and
        the joint index each lies beyond."""
        rb, h, n = self.rb, self.h, self.n
        centres = np.vstack([(joints[:-1] + joints[1:]) / 2, (joints[-1] + end) / 2])
        masses = np.full(n, rb.mass_per_length * h)
        masses[-1] /= 2
        arms, carried = rb.point_masses()
        points = np.vstack([centres, end + arms[:, None] * tangent])
        mass = np.concatenate([masses, carried])
        beyond = np.concatenate([np.arange(n), np.full(len(carried), n - 1)])
        return mass, points, beyond

    def energy_and_gradient(self, u: np.ndarray, command: np.ndarray, lam: float):
        rb, n, h = self.rb, self.n, self.h
        w2 = u[: 2 * n]
        angles = u[2 * n :] if self.torsion else command
        w, frames, joints, end = self._shape(w2)
        frame = frames[n]
        tangent = frame[:, 0]
        centres = rb.ring_centres(end, tangent)
        moments = lam * ring_moments(frame, angles, rb.moment)
        b, grad = self.field.with_gradient(centres)
        forces = np.einsum("kij,ki->kj", grad, moments)
        torques = np.cross(moments, b)
        energy = rb.ei / (2 * h) * np.sum(w2**2) - np.sum(moments * b)
        # Loads beyond each joint: force sum and moment about the origin, then about it.
        total_force = np.zeros((n, 3))
        total_moment = np.zeros((n, 3))
        ring_force = forces.sum(axis=0)
        ring_moment = torques.sum(axis=0) + np.cross(centres, forces).sum(axis=0)
        total_force[:] = ring_force
        total_moment[:] = ring_moment
        if self.gravity:
            g = lam * rb.gravity
            mass, points, beyond = self._masses(joints, end, tangent)
            energy -= np.sum(mass * (points @ g))
            weights = mass[:, None] * g
            f_joint = np.zeros((n, 3))
            m_joint = np.zeros((n, 3))
            np.add.at(f_joint, beyond, weights)
            np.add.at(m_joint, beyond, np.cross(points, weights))
            total_force += np.cumsum(f_joint[::-1], axis=0)[::-1]
            total_moment += np.cumsum(m_joint[::-1], axis=0)[::-1]
        about = total_moment - np.cross(joints, total_force)  # moment of loads beyond k
        # dE/d(spatial rotation at joint k) = -about_k; in the joint's body coordinates:
        body = np.einsum("kji,kj->ki", frames[1:], -about)
        grad_w = np.einsum("kji,kj->ki", _right_jacobian(w), body)[:, 1:]
        gradient = rb.ei / h * w2 + grad_w.ravel()
        if not self.torsion:
            return energy, gradient
        twist = angles - rb.commanded(command)
        coupling = lam**2 * rb.k12
        contact, contact_slope = rb.stop_contact(angles)
        energy += (
            np.sum(rb.gj / (2 * rb.length) * twist**2)
            + coupling * np.cos(angles[0] - angles[1])
            + contact
        )
        dm = (
            lam
            * rb.moment
            * (-np.sin(angles)[:, None] * frame[:, 1] + np.cos(angles)[:, None] * frame[:, 2])
        )
        s = np.sin(angles[0] - angles[1])
        grad_a = (
            rb.gj / rb.length * twist
            - np.sum(dm * b, axis=1)
            + (contact_slope - coupling * s) * np.array([1.0, -1.0])
        )
        return energy, np.concatenate([gradient, grad_a])

    def start(self, command: np.ndarray) -> np.ndarray:
        u = np.zeros(2 * self.n + (2 if self.torsion else 0))
        if self.torsion:
            u[2 * self.n :] = self.rb.commanded(command)
        return u

    def tip(self, u: np.ndarray) -> np.ndarray:
        """The tracked point (the proximal ring's centre). [m]"""
        _, frames, _, end = self._shape(u[: 2 * self.n])
        return end + self.rb.offset * frames[self.n][:, 0]

    def clearance(self, design: Design, u: np.ndarray) -> float:
        """:func:`ring_clearance` of the chain's rings. [m]"""
        _, frames, _, end = self._shape(u[: 2 * self.n])
        tangent = frames[self.n][:, 0]
        return ring_clearance(design, end + self.rb.offset * tangent, tangent)

    def relax(self, u: np.ndarray, command: np.ndarray, lam: float, tight: bool) -> np.ndarray:
        result = minimize(
            self.energy_and_gradient,
            u,
            args=(command, lam),
            jac=True,
            method="L-BFGS-B",
            options={
                "maxiter": 20000,
                "maxcor": 30,
                "ftol": 1e-16 if tight else 1e-12,
                "gtol": 1e-14 if tight else 1e-10,
            },
        )
        return result.x


def chain_state(
    design: Design,
    effects: frozenset[str],
    command: np.ndarray,
    ramp: int = 40,
    links: int = 100,
) -> tuple[Chain, np.ndarray, np.ndarray, float]:
    """The chain's state at ``command`` (2,) [rad]: its energy minimised at each step of the
    load ramp from the straight robot. Returns (chain, unknowns, tip position (3,), the
    smallest :func:`ring_clearance` at the states of the ramp [m])."""
    chain = Chain(design, effects, links)
    u = chain.start(command)
    clearance = np.inf
    for lam in np.linspace(0.0, 1.0, ramp + 1)[int(chain.rb.stops is None) :]:
        u = chain.relax(u, command, lam, tight=lam == 1.0)
        clearance = min(clearance, chain.clearance(design, u))
    return chain, u, chain.tip(u), clearance


def energy_hessian_eigenvalues(chain: Chain, u: np.ndarray, command: np.ndarray) -> np.ndarray:
    """Eigenvalues of the chain's energy Hessian at ``u`` by central differences of the
    gradient, scaled by the joints' bending stiffness EI / h (1 for the bare rod)."""
    return np.linalg.eigvalsh(_hessian(chain, u, command)) / (chain.rb.ei / chain.h)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rod_frames(
    design: Design, effects: frozenset[str], base_wrench: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """Frames (k, 3, 3) of the Kirchhoff rod at arc lengths ``points`` [m], integrated
    anew (scipy's DOP853) from the clamp with the base force and moment ``base_wrench``
    (6,) [N, N m]: p' = t, R' = [omega] R with omega = (m - (t.m) t) / EI (bending only),
    m' = n x t, n = n0 - q s (q the rod's weight per length with gravity)."""
    rb = robot(design, "printed_tip" in effects)
    q = rb.mass_per_length * rb.gravity if "gravity" in effects else np.zeros(3)
    n0, m0 = base_wrench[:3], base_wrench[3:]

    def rhs(s, y):
        frame = y[3:12].reshape(3, 3)
        t, m = frame[:, 0], y[12:15]
        omega = (m - (t @ m) * t) / rb.ei
        return np.concatenate([t, (_skew(omega) @ frame).ravel(), np.cross(n0 - q * s, t)])

    y0 = np.concatenate([np.zeros(3), np.eye(3).ravel(), m0])
    sol = solve_ivp(rhs, (0.0, rb.rod), y0, method="DOP853", t_eval=points, rtol=1e-12, atol=1e-14)
    frames = sol.y[3:12].T.reshape(-1, 3, 3)
    u, _, vt = np.linalg.svd(frames)  # re-orthonormalise
    return u @ vt


def chain_unknowns(chain: Chain, frames: np.ndarray, tip_angles: np.ndarray) -> np.ndarray:
    """The chain's unknowns that put its links along a rod with ``frames`` (n + 1, 3, 3) at
    s = k h (the links' centres): each joint's rotation log(R_k^T R_k+1), its twist dropped
    (zero for a rod without twist, to the order of h^2); then the tip angles with
    torsion."""
    w = Rotation.from_matrix(np.einsum("kji,kjl->kil", frames[:-1], frames[1:])).as_rotvec()
    u = w[:, 1:].ravel()
    return np.concatenate([u, tip_angles]) if chain.torsion else u


def _hessian(chain: Chain, u: np.ndarray, command: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """The chain's energy Hessian at u by central differences of its gradient, symmetrised."""
    n = u.size
    hess = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = step
        hess[:, i] = (
            chain.energy_and_gradient(u + e, command, 1.0)[1]
            - chain.energy_and_gradient(u - e, command, 1.0)[1]
        ) / (2 * step)
    return 0.5 * (hess + hess.T)


def chain_equilibrium_near(
    chain: Chain, u: np.ndarray, command: np.ndarray, iterations: int = 6
) -> np.ndarray:
    """The chain's equilibrium (of any stability) next to u: Newton on its energy gradient
    with the finite-difference Hessian."""
    for _ in range(iterations):
        g = chain.energy_and_gradient(u, command, 1.0)[1]
        if np.abs(g).max() < 1e-12 * chain.rb.ei / chain.h:
            break
        u = u - np.linalg.solve(_hessian(chain, u, command), g)
    return u

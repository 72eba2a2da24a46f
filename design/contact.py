"""The state with contact: the tip pressed against rigid obstacles (:mod:`design.obstacles`).

Contact is a unilateral constraint, solved exactly, not as a penalty: at the state the gap
g between the tip's body and the obstacle and the normal force lambda the obstacle exerts
satisfy g >= 0, lambda >= 0 and g lambda = 0 to CONTACT_TOLERANCE (m). The obstacle's
force lambda nu (nu its unit normal at the contact point q, pointing into the robot's
side) acts on the tip at q: the model's applied wrench at the tracked point P
(:mod:`design.registry` ``applied_force_*``, ``applied_moment_*``) is (lambda nu,
(q - P) x lambda nu), so the equilibrium is the model's own residual, every load
included.

For each configuration (:func:`solve_in_contact`): the state without obstacles first (the
load ramp, :func:`design.equilibrium.solve_equilibria`); where its body would be inside
an obstacle, the robot is pressed onto it: Newton on lambda for g(lambda) = 0 with the
slope dg/dlambda = nu^T C nu from the tip's compliance C (:mod:`design.stiffness`), each
iterate's state solved by Newton from the last, judged by the exact check; lambda is
kept >= 0. This is the load ramp's state wherever the tip approaches the obstacle
monotonically as the loads come up (the usual case: a wall in the way of the deflection);
a ramp along which the tip would touch and leave again, falls and folds in contact, and
two obstacles touched at once are not followed (the last ends in NaN, saying why).
Frictionless (a ``friction`` coefficient is not yet used). SI units (m, N).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from design.equilibrium import Equilibria, solve_equilibria
from design.equilibrium.newton import _check, _Checks, _newton
from design.model import PRINTED_TIP, RingPairModel
from design.obstacles import TipBody, gaps, tip_body
from design.records import Design, Obstacle
from design.registry import index
from design.stiffness import TipStiffness, tip_stiffness

CONTACT_TOLERANCE = 1e-9
"""|gap| below this is contact; a gap above -this is outside. [m]"""
CONTACT_ITERATIONS = 40
"""Newton iterations on the contact force per configuration at most."""

FORCE = index("applied_force_x")
MOMENT = index("applied_moment_x")


@dataclass(frozen=True)
class Contact:
    """Contact at N states (NaN where a row has no state).

    in_contact : shape (N,), the tip presses on an obstacle.
    obstacle : shape (N,), which (index into the obstacles; -1 none).
    point : shape (N, 3), the contact point on the tip's body (NaN without contact),
        base frame. [m]
    force : shape (N, 3), the force the tip exerts on the obstacle (0 without contact),
        base frame. [N]
    gap : shape (N,), the smallest gap to any obstacle (0 in contact). [m]
    normal : shape (N, 3), the obstacle's unit normal at the contact point (NaN without
        contact): the direction the tip is held in. [-]
    params : shape (k, N), each state's parameters, the contact's wrench applied at the
        tracked point (what the state solves; e.g. for :func:`design.stiffness.tip_stiffness`).
    """

    in_contact: np.ndarray
    obstacle: np.ndarray
    point: np.ndarray
    force: np.ndarray
    gap: np.ndarray
    normal: np.ndarray
    params: np.ndarray


def _all_gaps(
    obstacles: list[Obstacle], position: np.ndarray, tangent: np.ndarray, body: TipBody
) -> np.ndarray:
    """Gaps (K obstacles, N). [m]"""
    return np.array([gaps(o, position, tangent, body)[0] for o in obstacles]).reshape(
        len(obstacles), len(position)
    )


def _loaded(params: np.ndarray, cols: int, force: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """Per-column parameters (k, cols) with the wrench (3, cols) each added to the applied
    one (the contact's, on top of any the caller applies)."""
    p = np.tile(params[:, None], (1, cols)) if params.ndim == 1 else params.copy()
    p[FORCE : FORCE + 3] += force
    p[MOMENT : MOMENT + 3] += moment
    return p


def solve_in_contact(
    model: RingPairModel,
    params: np.ndarray,
    theta1: ArrayLike,
    theta2: ArrayLike,
    obstacles: list[Obstacle],
    body: TipBody,
    *,
    multistable: bool = False,
) -> tuple[Equilibria, Contact]:
    """The state of each configuration (commanded ring angles [rad]) with ``obstacles``
    present, and its contact (module docstring). ``params`` shape (k,), or one column per
    configuration, (k, N) (e.g. a moved magnet, :mod:`design.moving`). [SI]"""
    params = np.asarray(params, float)
    eq = solve_equilibria(model, params, theta1, theta2, multistable=multistable)
    n = len(eq)
    contact = Contact(
        in_contact=np.zeros(n, bool),
        obstacle=np.full(n, -1),
        point=np.full((n, 3), np.nan),
        force=np.zeros((n, 3)),
        gap=np.full(n, np.inf),
        normal=np.full((n, 3), np.nan),
        params=np.tile(params[:, None], (1, n)) if params.ndim == 1 else params.copy(),
    )
    if not obstacles or n == 0:
        return eq, contact
    g = _all_gaps(obstacles, eq.position, eq.tangent, body)
    g = np.where(np.isfinite(eq.position).all(axis=1), g, np.nan)
    contact.gap[:] = np.min(g, axis=0) if len(obstacles) else np.inf
    pressed = np.flatnonzero(contact.gap < -CONTACT_TOLERANCE)
    if pressed.size == 0:
        return eq, contact
    which = np.argmin(np.nan_to_num(g[:, pressed], nan=np.inf), axis=0)
    x, p, force, point, ok, why = _press(
        model,
        contact.params[:, pressed],
        eq.command[pressed].T,
        eq.unknowns[pressed].T,
        obstacles,
        which,
        body,
    )
    fields = {k: v.copy() for k, v in eq.__dict__.items()}
    converged, stable, outs = _check(model, p, eq.command[pressed].T, x)
    position, tangent = outs[2].T, outs[3][0:3].T
    for k, o in enumerate(obstacles):  # no other obstacle may be entered
        entered = (gaps(o, position, tangent, body)[0] < -CONTACT_TOLERANCE) & (which != k)
        why[entered & ok] = "the tip touches two obstacles at once (not modelled)"
        ok &= ~entered
    ok &= converged & stable
    nan = np.where(ok, 1.0, np.nan)
    frames = outs[3].T.reshape(-1, 3, 3).transpose(0, 2, 1) * nan[:, None, None]
    fields["position"][pressed] = outs[2].T * nan[:, None]
    fields["frame"][pressed] = frames
    fields["tangent"][pressed] = frames[:, :, 0]
    fields["tip_angles"][pressed] = outs[4].T * nan[:, None]
    fields["unknowns"][pressed] = x.T * nan[:, None]
    fields["residual"][pressed] = np.max(np.abs(outs[0]), axis=0)
    for flag in ("converged", "stable"):
        fields[flag][pressed] = ok
    fields["snapped"][pressed] &= ok
    fields["multistable"][pressed] &= ok
    fields["failure"][pressed] = np.where(ok, "", why)
    contact.in_contact[pressed] = ok
    contact.obstacle[pressed] = np.where(ok, which, -1)
    contact.point[pressed] = point * nan[:, None]
    contact.force[pressed] = force * nan[:, None]
    contact.gap[pressed] = np.where(ok, 0.0, np.nan)
    lam = np.linalg.norm(force, axis=1)
    contact.normal[pressed] = -force / np.where(lam > 0, lam, np.nan)[:, None] * nan[:, None]
    contact.params[:, pressed] = p
    return Equilibria(**fields), contact


def solve_design_in_contact(
    design: Design,
    model: RingPairModel,
    theta1: ArrayLike,
    theta2: ArrayLike,
    *,
    multistable: bool = False,
    params: np.ndarray | None = None,
) -> tuple[Equilibria, TipStiffness, Contact]:
    """The states of ``design`` for commanded angles [rad] with its obstacles
    (``environment.obstacles``; none: the free states), their tip stiffness (held on the
    obstacle where the tip presses on one) and their contact; ``model`` for ``design``'s
    field (:meth:`RingPairModel.for_design`). ``params``: one column per configuration
    (k, N) where they differ from the design's (a moved magnet, :mod:`design.moving`)."""
    model = model.for_design(design)
    params = model.parameters(design) if params is None else params
    body = tip_body(design, printed=PRINTED_TIP in model.effects)
    obstacles = list(design.environment.obstacles)
    eq, contact = solve_in_contact(
        model, params, theta1, theta2, obstacles, body, multistable=multistable
    )
    return eq, tip_stiffness(model, contact.params, eq, held=contact.normal), contact


def _press(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    obstacles: list[Obstacle],
    which: np.ndarray,
    body: TipBody,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Press the states x (n, m), of parameters ``params`` (k, m), onto obstacles ``which``
    (m,): (states, their parameters
    with the contact's applied wrench (k, m), force on the obstacle (m, 3) [N], contact
    point (m, 3) [m], found, why not)."""
    m = x.shape[1]
    lam = np.zeros(m)
    force = np.zeros((3, m))
    moment = np.zeros((3, m))
    point = np.full((m, 3), np.nan)
    done = np.zeros(m, bool)
    alive = np.isfinite(x).all(axis=0)
    why = np.full(m, "", dtype=object)
    for _ in range(CONTACT_ITERATIONS):
        a = np.flatnonzero(alive & ~done)
        if a.size == 0:
            break
        p = _loaded(params[:, a], a.size, force[:, a], moment[:, a])
        _, _, outs = _check(model, p, command[:, a], x[:, a])
        position, tangent = outs[2].T, outs[3][0:3].T
        gap = np.full(a.size, np.nan)
        nu = np.zeros((a.size, 3))
        q = np.zeros((a.size, 3))
        for k, o in enumerate(obstacles):
            mine = which[a] == k
            if mine.any():
                gk, qk, nk = gaps(o, position[mine], tangent[mine], body)
                gap[mine], q[mine], nu[mine] = gk, qk, nk
        point[a] = q
        settled = np.abs(gap) <= CONTACT_TOLERANCE
        done[a[settled]] = True
        go = ~settled & np.isfinite(gap)
        alive[a[~np.isfinite(gap)]] = False
        why[a[~np.isfinite(gap)]] = "the tip's body went inside an obstacle"
        a, gap, nu, q, position = a[go], gap[go], nu[go], q[go], position[go]
        if a.size == 0:
            continue
        eq_like = Equilibria(
            command=command[:, a].T,
            tip_angles=outs[4][:, go].T,
            position=position,
            tangent=tangent[go],
            frame=np.zeros((a.size, 3, 3)),
            unknowns=x[:, a].T,
            converged=np.ones(a.size, bool),
            stable=np.ones(a.size, bool),
            residual=np.zeros(a.size),
            snapped=np.zeros(a.size, bool),
            multistable=np.zeros(a.size, bool),
            failure=np.full(a.size, "", dtype=object),
        )
        c = tip_stiffness(model, p[:, go], eq_like).compliance
        slope = np.einsum("ki,kij,kj->k", nu, c, nu)
        step = np.where(slope > 0, -gap / np.where(slope > 0, slope, 1.0), np.nan)
        lam[a] = np.maximum(lam[a] + step, 0.0)
        released = lam[a] == 0.0  # (the tip lifts off: it was no contact)
        f = lam[a][:, None] * nu
        force[:, a] = f.T
        moment[:, a] = np.cross(q - position, f).T
        p = _loaded(params[:, a], a.size, force[:, a], moment[:, a])
        states, converged, good = _newton(
            model,
            p,
            command[:, a],
            x[:, a],
            np.ones(a.size),
            _Checks(a.size),
            np.arange(a.size),
            exact=True,
        )
        x[:, a] = states
        lost = ~(converged & good) | ~np.isfinite(step) | released
        alive[a[lost]] = False
        why[a[lost]] = "no stable state pressed on the obstacle was found"
    why[alive & ~done] = "the contact force did not converge"
    found = done & alive
    return x, _loaded(params, m, force, moment), -force.T, point, found, why

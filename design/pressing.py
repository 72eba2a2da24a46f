"""The ring angles that press the tip on the design's obstacles with a given force: the
inverse of the force map (:mod:`design.contact`), ``ringpair steer --press``.

Frictionless contact holds the force along the obstacle's normal, so a wanted force is a
magnitude; with two ring angles the angles that press with it form curves in the
(theta1, theta2) plane, the contour of the force map at that magnitude. They are found
where they cross the lines of the ring grid: on every grid edge whose ends press less and
more than wanted (a free end counts as 0), the crossing is bracketed and located by the
Illinois variant of regula falsi, each iterate a state solved with contact, to
PRESS_TOLERANCE. An edge across which the force jumps (a snap, a state lost, the tip
passing to another obstacle) has no crossing and gives none. The answers sample each
curve at the grid's resolution: a finer grid samples it more densely. SI units (rad, N).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.contact import Contact, solve_design_in_contact
from design.equilibrium import Equilibria
from design.model import RingPairModel
from design.records import Design
from design.stiffness import TipStiffness
from design.workspace import angle_grid

PRESS_TOLERANCE = 1e-7
"""An answer presses within this of the wanted force (0.0001 mN). [N]"""
PRESS_ITERATIONS = 60
"""Regula falsi iterations per crossing at most."""


@dataclass(frozen=True)
class Pressing:
    """The angles that press with ``wanted`` on the ring grid of ``grid`` angles.

    wanted : the force's magnitude asked for. [N]
    grid : shape (G,), the grid's angles of either ring. [rad]
    magnitude : shape (G, G), the force map, [i, j] at (grid[i], grid[j]); 0 where the
        tip is free, NaN where it has no state. [N]
    theta : shape (R, 2), the answers' ring angles in [0, 2 pi). [rad]
    equilibria, stiffness, contact : the answers' states, tip stiffness and contact.
    crossings : grid edges the force crossed ``wanted`` on (each is an answer or a jump).
    jumps : of those, where the force jumps across it instead (no answer there).
    """

    wanted: float
    grid: np.ndarray
    magnitude: np.ndarray
    theta: np.ndarray
    equilibria: Equilibria
    stiffness: TipStiffness
    contact: Contact
    crossings: int
    jumps: int


def _magnitude(eq: Equilibria, contact: Contact) -> np.ndarray:
    """|force on the obstacle| (0 free), NaN without a state. [N]"""
    return np.where(eq.stable, np.linalg.norm(contact.force, axis=1), np.nan)


def press(design: Design, model: RingPairModel, wanted: float, step: float) -> Pressing:
    """The ring angles at which ``design``'s tip presses on its obstacles with the force
    ``wanted`` [N] (> 0), found on the crossings of a grid of ``step`` [rad]."""
    grid = angle_grid(step)
    g = grid.size
    t1, t2 = (a.ravel() for a in np.meshgrid(grid, grid, indexing="ij"))
    eq, _, contact = solve_design_in_contact(design, model, t1, t2)
    magnitude = _magnitude(eq, contact).reshape(g, g)
    # Edges along theta1 then theta2, periodic: (start index, direction).
    i, j = np.meshgrid(np.arange(g), np.arange(g), indexing="ij")
    starts, ends, directions = [], [], []
    for di, dj in ((1, 0), (0, 1)):
        starts.append(np.stack([i.ravel(), j.ravel()], 1))
        ends.append(np.stack([(i.ravel() + di) % g, (j.ravel() + dj) % g], 1))
        directions.append(np.tile([di, dj], (g * g, 1)))
    start, end, direction = (np.concatenate(a) for a in (starts, ends, directions))
    fa = magnitude[start[:, 0], start[:, 1]] - wanted
    fb = magnitude[end[:, 0], end[:, 1]] - wanted
    crossing = np.isfinite(fa) & np.isfinite(fb) & (np.sign(fa) * np.sign(fb) < 0)
    origin = grid[start[crossing]]
    delta = direction[crossing] * (2 * np.pi / g)
    theta, result = _locate(design, model, wanted, origin, delta, fa[crossing], fb[crossing])
    found = np.abs(_magnitude(*result[::2]) - wanted) <= PRESS_TOLERANCE
    eq_found, stiffness, contact_found = (_rows(r, found) for r in result)
    return Pressing(
        wanted=wanted,
        grid=grid,
        magnitude=magnitude,
        theta=np.mod(theta[found], 2 * np.pi),
        equilibria=eq_found,
        stiffness=stiffness,
        contact=contact_found,
        crossings=int(crossing.sum()),
        jumps=int((~found).sum()),
    )


def _locate(
    design: Design,
    model: RingPairModel,
    wanted: float,
    origin: np.ndarray,
    delta: np.ndarray,
    fa: np.ndarray,
    fb: np.ndarray,
) -> tuple[np.ndarray, tuple[Equilibria, TipStiffness, Contact]]:
    """The crossings of f(s) = |force at origin + s delta| - wanted on s in [0, 1] (f(0)
    = fa, f(1) = fb of opposite signs), all edges at once: the Illinois variant of regula
    falsi (the end kept twice in a row has its value halved), which keeps the bracket and
    converges superlinearly where f is smooth; where it jumps the bracket shrinks onto the
    jump and the state there misses ``wanted`` (no answer). Returns the last iterates'
    angles (n, 2) [rad] and their (states, stiffness, contact)."""
    n = origin.shape[0]
    a, b = np.zeros(n), np.ones(n)
    fa, fb = fa.copy(), fb.copy()
    side = np.zeros(n, int)  # which end was kept last: -1 a, +1 b
    s = np.full(n, 0.5)
    active = np.ones(n, bool)
    result = None
    for _ in range(PRESS_ITERATIONS):
        if result is not None and not active.any():
            break
        s_new = (a * fb - b * fa) / (fb - fa)
        s = np.where(active, s_new, s)
        theta = origin + s[:, None] * delta
        k = np.flatnonzero(active) if result is not None else np.arange(n)
        part = solve_design_in_contact(design, model, theta[k, 0], theta[k, 1])
        result = part if result is None else _assign(result, k, part)
        f = _magnitude(part[0], part[2]) - wanted
        lost = ~np.isfinite(f)
        done = np.abs(f) <= PRESS_TOLERANCE
        low = (np.sign(f) == np.sign(fa[k])) & ~lost
        kl, kh = k[low], k[~low & ~lost]
        a[kl], fa[kl] = s[kl], f[low]
        fb[kl] = np.where(side[kl] == -1, fb[kl] / 2, fb[kl])  # a moved again: halve b
        side[kl] = -1
        b[kh], fb[kh] = s[kh], f[~low & ~lost]
        fa[kh] = np.where(side[kh] == 1, fa[kh] / 2, fa[kh])
        side[kh] = 1
        active[k[done | lost | (b[k] - a[k] < 1e-12)]] = False
    assert result is not None
    return origin + s[:, None] * delta, result


def _assign(result, k: np.ndarray, part):  # noqa: ANN001, ANN202 - three record kinds
    """``result``'s records (states, stiffness, contact; rows along the first axis, or
    the second for contact's params) with rows ``k`` replaced by ``part``'s."""
    out = []
    for whole, new in zip(result, part, strict=True):
        fields = {}
        for name, value in vars(whole).items():
            v = np.array(value, copy=True)
            if isinstance(value, np.ndarray) and name == "params":
                v[:, k] = getattr(new, name)
            elif isinstance(value, np.ndarray) and value.ndim:
                v[k] = getattr(new, name)
            else:
                v = value
            fields[name] = v
        out.append(type(whole)(**fields))
    return tuple(out)


def _rows(record, keep: np.ndarray):  # noqa: ANN001, ANN202 - three record kinds
    """``record`` with only the rows ``keep`` (contact's params along its columns)."""
    fields = {}
    for name, value in vars(record).items():
        if isinstance(value, np.ndarray) and name == "params":
            fields[name] = value[:, keep]
        elif isinstance(value, np.ndarray) and value.ndim:
            fields[name] = value[keep]
        else:
            fields[name] = value
    return type(record)(**fields)


__all__ = ["PRESS_TOLERANCE", "Pressing", "press"]

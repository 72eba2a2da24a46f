"""The fall: the stable state the robot goes down its total potential energy into, from
a fold of the load ramp or an unstable equilibrium (saddle-free Newton)."""

from __future__ import annotations

import numpy as np

from design.equilibrium import settings
from design.equilibrium.kernels import kernels
from design.equilibrium.newton import _Checks, _newton
from design.equilibrium.stability import _columns, _norm, _scale
from design.model import RingPairModel


def _fall(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stable states the robot falls into from x at load factors lam (a fold, or an
    unstable equilibrium).

    The robot goes down its total potential energy. In the modes of M = G^-1 H (H the
    energy's Hessian in the unknowns, G a metric: :class:`design.model.RingPairModel`
    ``descent``; eigenvectors v, eigenvalues mu, the stiffness of each mode relative to
    the elastic one) the downhill direction -G^-1 g has components -a; each mode moves by
    -a / |mu| (with |mu| at least MODE_FLOOR): Newton's step in the stable modes, and in
    an unstable mode the same
    distance downhill instead of up to the saddle ("saddle-free Newton": Dauphin et al.,
    NeurIPS 2014), the whole step at most TRUST long. It starts kicked by KICK both ways
    along the softest mode, so that a symmetric bifurcation is left too, and is polished by
    Newton once no mode is unstable and its step or pull is small, judged by the exact
    check (a polish that lands on an unstable equilibrium kicks the column off again). A
    way on which the rings reach the external magnet ends there (contact, which is not
    modelled). Of the two ways the stable state nearer x is taken (the first where they
    tie to TIE: at a symmetric bifurcation the states are mirror images).
    Returns (states, found, touched: no state found and the fall reached the magnet)."""
    kern = kernels(model)
    n, m = x.shape
    both = np.concatenate([np.arange(m), np.arange(m)])
    p2, c2, lam2 = _columns(params, both), command[:, both], lam[both]
    scale = _scale(model, p2, 2 * m)
    xs = np.concatenate([x, x], axis=1)
    sign = np.concatenate([np.ones(m), -np.ones(m)])
    found = np.zeros(2 * m, bool)
    touched = np.zeros(2 * m, bool)
    alive = np.isfinite(xs).all(axis=0)
    kicked = np.zeros(2 * m, bool)
    polishes = np.zeros(2 * m, int)
    scratch = _Checks(2 * m)
    for _ in range(settings.FALL_ITERATIONS):
        a = np.flatnonzero(alive & ~found)
        if a.size == 0:
            break
        direction, modes, clearance = kern.run(
            "descent", [xs[:, a], c2[:, a], lam2[None, a]], _columns(p2, a)
        )
        matrices = modes.T.reshape(-1, n, n).transpose(0, 2, 1)
        inside = ~(clearance[0] >= 0)
        touched[a[inside]] = True
        good = np.isfinite(matrices).all(axis=(1, 2)) & np.isfinite(direction).all(axis=0)
        good &= ~inside
        alive[a[~good]] = False
        a, direction, matrices = a[good], direction[:, good], matrices[good]
        if a.size == 0:
            continue
        values, vectors = np.linalg.eig(matrices)
        fresh = ~kicked[a]
        if fresh.any():  # leave along the softest mode, both ways
            soft = vectors[np.flatnonzero(fresh), :, np.argmin(values.real[fresh], axis=1)].real
            relative = soft.T / scale[:, a[fresh]]
            # (a mode's sign is arbitrary: its first component of at least half the largest
            # magnitude counts positive, so that a symmetric mode's sign, and the side the
            # robot falls to at a symmetric bifurcation, does not depend on rounding)
            size = np.abs(relative)
            first = np.argmax(size >= 0.5 * size.max(axis=0), axis=0)
            lead = relative[first, np.arange(relative.shape[1])]
            big = size.max(axis=0)
            kick = settings.KICK * np.sign(lead) / np.where(big > 0, big, 1.0)
            xs[:, a[fresh]] += sign[a[fresh]] * kick * soft.T
            kicked[a[fresh]] = True
        pulls = direction.T[:, :, None].astype(complex)
        try:
            components = np.linalg.solve(vectors, pulls)[:, :, 0]
        except np.linalg.LinAlgError:  # a repeated eigenvalue's eigenvectors can be
            # dependent (drawn source set, seed 2488198026): the least-squares components
            components = (np.linalg.pinv(vectors) @ pulls)[:, :, 0]
        magnitude = np.maximum(np.abs(values.real), settings.MODE_FLOOR)
        step = np.einsum("kij,kj->ki", vectors, components / magnitude).real.T
        size = _norm(step, scale[:, a])
        step *= np.minimum(1.0, settings.TRUST / np.maximum(size, 1e-300))
        xs[:, a] -= step
        # Polished where no mode is unstable (within MODE_FLOOR: near a straight rod the
        # axial force and moment are constraint-like, the energy hardly depends on them and
        # the steps along them need not shrink) and the step or the pull is small.
        pull = _norm(direction, scale[:, a])
        settled = (values.real > -settings.MODE_FLOOR).all(axis=1)
        ready = a[settled & ((size < settings.POLISH_BELOW) | (pull < settings.POLISH_GRADIENT))]
        if ready.size:
            polished, _, ok = _newton(
                model,
                _columns(p2, ready),
                c2[:, ready],
                xs[:, ready],
                lam2[ready],
                scratch,
                ready,
                exact=True,
            )
            xs[:, ready[ok]] = polished[:, ok]
            found[ready[ok]] = True
            polishes[ready[~ok]] += 1
            kicked[ready[~ok]] = False  # near an unstable equilibrium: leave it again
            alive[ready[polishes[ready] > settings.POLISH_ATTEMPTS]] = False
    distance = np.where(found, _norm(xs - x[:, both], scale), np.inf)
    second = distance[m:] < distance[:m] * (1 - settings.TIE)
    pick = np.where(second, np.arange(m) + m, np.arange(m))
    if scratch.outs is not None:
        full = found[pick] & scratch.done[pick]
        checks.put(where[full], [o[:, pick[full]] for o in scratch.outs])
    contact = ~found[pick] & (touched[:m] | touched[m:])
    return xs[:, pick], found[pick], contact

"""The compiled functions of one model that the equilibrium solver calls, the loads
scaled by the load factor lambda, and their batched evaluation in chunks of columns."""

from __future__ import annotations

import threading
from functools import cache

import casadi as ca
import numpy as np

from design.compiled import ColumnEvaluator, compile_functions, map_threads, mapped
from design.equilibrium import settings
from design.model import RingPairModel
from design.registry import index


class _Kernels:
    """The compiled functions of one model that the solver calls, the loads scaled by the
    load factor lambda: ``newton`` (x, command, lambda, params) -> (r, Newton step,
    dx/dlambda, monitor, clearance), ``relaxation`` and ``descent`` as
    :class:`design.model.RingPairModel`'s;
    ``check`` (x, command, lambda, params) -> (r, exact monitor, position, frame (9,
    column-major), tip angles, clearance to the external magnet);
    ``leap<m>`` (command, params) -> (the tangent at rest dx/dlambda, taken, the state at
    full load, ``check``'s outputs there): the ramp in m equal steps in one call, with
    the ramp's acceptance tests (:meth:`_leap`); ``corrections``: PATH_CORRECTIONS Newton
    corrections at full load in one call (:meth:`_corrections`)."""

    def __init__(self, model: RingPairModel) -> None:
        self.model = model
        x = ca.SX.sym("x", model.n_unknowns)
        command = ca.SX.sym("command", 2)
        lam = ca.SX.sym("load_factor")
        prm = ca.SX.sym("params", model.residual.size1_in(2))
        load = index("load_scale")
        scaled = ca.vertcat(prm[:load], prm[load] * lam, prm[load + 1 :])
        r_lam, step, load_tangent, monitor_lam, clearance = model.newton.call([x, command, scaled])
        newton = ca.Function(
            "newton",
            [x, command, lam, prm],
            [r_lam, step, load_tangent * prm[load], monitor_lam, clearance],  # dx / dlambda
        )
        relaxation, descent = (
            ca.Function(
                name, [x, command, lam, prm], getattr(model, name).call([x, command, scaled])
            )
            for name in ("relaxation", "descent")
        )
        r, monitor, position, frame, angles, clearance = model.check.call([x, command, scaled])
        check = ca.Function(
            "check",
            [x, command, lam, prm],
            [r, monitor, position, ca.reshape(frame, 9, 1), angles, clearance],
        )
        leaps = [
            self._leap(model, newton, relaxation, check, command, prm, count)
            for count in range(1, settings.LEAP_STEPS + 1)
            if model.linear_rod
        ]
        compiled = compile_functions([newton, relaxation, descent, check, *leaps])
        self.newton, self.relaxation, self.descent, self.check = compiled[:4]
        for leap in compiled[4:]:  # run by name: "leap1", "leap2", ...
            setattr(self, leap.name(), leap)
        self.corrections = self._corrections(model, self.newton)
        self._maps: dict[tuple[str, int, int], ColumnEvaluator] = {}
        self._tiles: dict[tuple[bytes, int], np.ndarray] = {}
        self._lock = threading.Lock()

    @staticmethod
    def _leap(
        model: RingPairModel,
        newton: ca.Function,
        relaxation: ca.Function,
        check: ca.Function,
        command: ca.SX,
        prm: ca.SX,
        count: int,
    ) -> ca.Function:
        """``leap<count>`` (command, params) -> (the tangent at rest dx/dlambda, taken (1 or
        0), the state at full load, ``check``'s outputs there): the ramp in ``count`` equal
        steps, taken exactly where :func:`_ramp` would accept each step: the first
        predicts a change of at most FIRST_DISPLACEMENT; in each, the first correction
        stays within :func:`_near` of the prediction and each later one contracts by
        CONTRACTION up to the first that converges (residual below the tolerance at the
        step's load, or a step below :func:`_step_tolerance`; later ones only polish the
        state to rounding); below full load no fold is crossed and at full load the state
        passes the exact check; the rings stay clear of the external magnet. For the
        linear rod (the only one with leaps) both the fold monitor and the exact one are
        the Sylvester minors of the stiffness form, all positive where stable."""
        probe = np.zeros(prm.size1())
        probe[index("free_length")] = 2.0
        length = prm[index("free_length")]
        scale = ca.vertcat(*[length if v == 2.0 else 1 for v in model.unknown_scale(probe)])

        def norm(v: ca.SX) -> ca.SX:
            return ca.mmax(ca.fabs(v) / scale)

        def positive(v: ca.SX) -> ca.SX:
            return ca.mmin(v) > 0

        x = model.initial.call([command, prm])[0]
        # The tangent at rest: (dr/dx)^-1 = K^-1 there, and r is linear in the load (but
        # for the rings' mutual torque, which goes with its square), so it is minus the
        # relaxation direction at full load.
        tangent = -relaxation.call([x, command, 1, prm])[0]
        ok = norm(tangent) <= count * settings.FIRST_DISPLACEMENT
        before, rest_tangent = None, tangent
        h = 1.0 / count
        for k in range(1, count + 1):
            move = h * tangent
            if before is not None:  # the ramp's second-order predictor
                move += 0.5 * h * (tangent - before)
            x = x + move
            lam = k * h
            tol = settings.TOLERANCE if lam >= 1.0 else settings.RAMP_TOLERANCE
            small = float(settings.step_tolerance(np.array([lam]))[0])
            going, converged = ca.SX(1), ca.SX(0)
            bound = ca.fmax(
                settings.CORRECTION_RATIO * norm(move), settings.MIN_CORRECTION
            )  # _near
            for _ in range(settings.LEAP_CORRECTIONS):
                r, step, load_tangent, monitor, clearance = newton.call([x, command, lam, prm])
                done = ca.logic_or(ca.mmax(ca.fabs(r)) < tol, ca.mmax(ca.fabs(step)) < small)
                converged = ca.logic_or(converged, ca.logic_and(going, done))
                size = norm(step)
                going = ca.logic_and(going, ca.logic_and(ca.logic_not(done), size <= bound))
                bound = settings.CONTRACTION * size
                x = x - step
            ok = ca.logic_and(ok, converged)
            if k < count:
                ok = ca.logic_and(ok, ca.logic_and(positive(monitor), clearance[0] >= 0))
            before, tangent = tangent, load_tangent
        checked = check.call([x, command, 1, prm])
        r, monitor, clearance = checked[0], checked[1], checked[5]
        exact = ca.logic_and(ca.mmax(ca.fabs(r)) < settings.TOLERANCE, positive(monitor))
        ok = ca.logic_and(ok, ca.logic_and(exact, clearance[0] >= 0))
        # NaN anywhere fails every comparison in numpy, not in C's fmax: say it here.
        ok = ca.logic_and(ok, ca.sum1(ca.fabs(ca.vertcat(x, r))) < np.inf)
        return ca.Function(f"leap{count}", [command, prm], [rest_tangent, ok, x, *checked])

    @staticmethod
    def _corrections(model: RingPairModel, newton: ca.Function) -> ca.Function:
        """``corrections`` (x, command, params, scale) -> (the state after each of
        PATH_CORRECTIONS Newton corrections from x at full load, (n, K); per correction
        its size max |step| / scale, max |step|, max |r| and sum |step| (C's fmax skips
        NaN, a sum does not), (4, K); the monitor and the clearance where each was taken,
        (m, K) and (1, K)). The compiled ``newton`` called K times in CasADi's virtual
        machine: nothing to compile, and the decisions (:func:`solve_sequence`) are
        those of the corrections made one by one, to the last bit."""
        x0 = ca.MX.sym("x", model.n_unknowns)
        command = ca.MX.sym("command", 2)
        prm = ca.MX.sym("params", newton.size1_in(3))
        scale = ca.MX.sym("scale", model.n_unknowns)
        x, states, sizes, monitors, clearances = x0, [], [], [], []
        for _ in range(settings.PATH_CORRECTIONS):
            r, step, _tangent, monitor, clearance = newton.call([x, command, 1.0, prm])
            magnitude = ca.fabs(step)
            sizes.append(
                ca.vertcat(
                    ca.mmax(magnitude / scale),
                    ca.mmax(magnitude),
                    ca.mmax(ca.fabs(r)),
                    ca.sum1(magnitude),
                )
            )
            monitors.append(monitor)
            clearances.append(clearance[0])
            x = x - step
            states.append(x)
        return ca.Function(
            "corrections",
            [x0, command, prm, scale],
            [
                ca.horzcat(*states),
                ca.horzcat(*sizes),
                ca.horzcat(*monitors),
                ca.horzcat(*clearances),
            ],
        )

    def _mapped(self, function: ca.Function, size: int) -> ColumnEvaluator:
        key = (function.name(), size, map_threads(size))
        with self._lock:
            if key not in self._maps:
                self._maps[key] = mapped(function, size)
            return self._maps[key]

    def _shared(self, params: np.ndarray, size: int) -> np.ndarray:
        """``params`` (k,) as the (k, size) column-major input of a map, kept for reuse (a
        shared input of a threaded map is far slower in CasADi, and copying it for each
        call costs about as much as a Newton step of the linear rod)."""
        key = (params.tobytes(), size)
        with self._lock:
            if key not in self._tiles:
                if len(self._tiles) >= 8:
                    self._tiles.clear()
                self._tiles[key] = np.tile(params, size).reshape(size, params.size).T
            return self._tiles[key]

    def run(
        self, which: str | ca.Function, args: list[np.ndarray], params: np.ndarray
    ) -> list[np.ndarray]:
        """Evaluate ``which`` (a kernel's name, or another function of the model whose last
        input is the parameters, e.g. :mod:`design.steering`'s) on the columns of ``args``
        (each (rows, N)) with ``params`` shared, shape (k,), or per column, (k, N); in
        chunks of CHUNK columns, the last one padded to a power of two below GRAIN and to a
        multiple of GRAIN above (few distinct map sizes, at most half the work wasted).
        Returns each output as (rows, N)."""
        f = getattr(self, which) if isinstance(which, str) else which
        n = args[0].shape[1]
        if n == 0:
            return [np.zeros((f.size1_out(i), 0)) for i in range(f.n_out())]
        outs: list[list[np.ndarray]] = []
        for start in range(0, n, settings.CHUNK):
            stop = min(start + settings.CHUNK, n)
            count = stop - start
            size = min(
                settings.CHUNK,
                -(-count // settings.GRAIN) * settings.GRAIN,
                1 << (count - 1).bit_length(),
            )
            chunk = [a[:, start:stop] for a in args]
            if params.ndim == 2:
                chunk.append(params[:, start:stop])
            if size > count:  # padded with the last column (np.pad's cost: a fit's 10 %)
                edge = np.minimum(np.arange(size), count - 1)
                chunk = [c[:, edge] for c in chunk]
            if params.ndim == 1:
                chunk.append(self._shared(params, size))
            results = self._mapped(f, size)(chunk)
            outs = outs or [[] for _ in results]
            for acc, out in zip(outs, results, strict=True):
                acc.append(out[:, :count])
        return [acc[0] if len(acc) == 1 else np.concatenate(acc, axis=1) for acc in outs]


@cache
def kernels(model: RingPairModel) -> _Kernels:
    """The compiled solver functions of ``model`` (built and compiled once per process,
    kept for every model: there is one per set of effects, and a diagnosis fits up to all
    32 of them; the shared library is cached on disk by :mod:`design.compiled`)."""
    return _Kernels(model)


def _initial(model: RingPairModel, params: np.ndarray, command: np.ndarray) -> np.ndarray:
    """The unloaded robot for each column (:attr:`RingPairModel.initial`: straight, the
    tip angles the commands, or with stops the rings against them)."""
    if model.n_unknowns == model.n_rod:
        return np.zeros((model.n_unknowns, command.shape[1]))
    return kernels(model).run(model.initial, [command], params)[0]

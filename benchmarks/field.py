"""Exact cylinder-field throughput: ringpair's compiled function against magpylib's
``Cylinder.getB`` on the same points, in one run.

The magnet is the demonstrator's external magnet in its pose (76.2 mm x 38.1 mm N52,
Br 1.45 T, centre 249.05 mm on x, magnetised along -x); the points lie outside it, from
its surface out to 10 diameters (a tenth of them within 1 mm of the surface, some on its
axis). Timings are the best of ``--repeat`` interleaved runs, wall clock, from an (n, 3)
array of points to an (n, 3) array of B [T] (and (n, 3, 3) of dB/dp [T/m]).

- headline: B alone, ringpair (compiled C, ``.map(n, "thread", THREADS)``) vs magpylib;
- B and its exact gradient from ringpair vs magpylib's B plus a central-difference
  gradient (7 getB calls), which is what one would do without ringpair;
- for information, ringpair with the batch loop compiled into the C code as well
  (``compile_function(fn.map(CHUNK))``), which removes CasADi's per-point call overhead;
- every other source kind of ``[[field.sources]]`` with a magpylib twin (``cuboid``,
  ``sphere``, ``coil``; :mod:`design.fields`) the same way, on ``--n-kinds`` points from
  1.2 to 5 of the source's extents around it: B against magpylib's ``Cuboid``,
  ``Sphere`` and ``Circle`` (their largest relative difference, and the ratio of
  throughputs), and B with its exact gradient against magpylib's B plus central
  differences (the gradients' median relative difference, and the ratio).

    python benchmarks/field.py [--n 100000] [--n-kinds 20000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import os
import time

import casadi as ca
import magpylib as magpy
import numpy as np
from scipy.spatial.transform import Rotation

from design.compiled import THREADS, compile_function
from design.cylinder_field import cylinder_field_function
from design.designfile import default_design
from design.fields.sources import KINDS, source_field, split_parameters

CHUNK = 1000


def outside_points(diameter: float, length: float, n: int, rng) -> np.ndarray:
    """(n, 3) points in the magnet frame (axis z) outside the magnet, up to 10 diameters."""
    a, b = diameter / 2, length / 2
    out = np.empty((0, 3))
    while len(out) < n:
        m = 2 * n
        rho = np.where(
            rng.random(m) < 0.1,
            a + rng.uniform(0, 1e-3, m),
            rng.uniform(0, 10 * diameter, m),
        )
        rho[rng.random(m) < 0.02] = 0.0  # on the axis
        z = rng.uniform(-10 * diameter, 10 * diameter, m)
        near_face = rng.random(m) < 0.05
        z[near_face] = np.sign(z[near_face]) * (b + rng.uniform(0, 1e-3, near_face.sum()))
        keep = (rho > a) | (np.abs(z) > b)
        phi = rng.uniform(0, 2 * np.pi, m)
        pts = np.c_[rho * np.cos(phi), rho * np.sin(phi), z][keep]
        out = np.vstack([out, pts])
    return out[:n]


def evaluate(function: ca.Function, columns: list[np.ndarray]) -> list[np.ndarray]:
    """Evaluate a mapped function on column-major buffers (no DM conversion), as
    ``design.equilibrium`` does; outputs as flat column-major arrays."""
    buf, trigger = function.buffer()
    flat = [np.asfortranarray(c).ravel(order="F") for c in columns]
    outs = [np.empty(function.nnz_out(i)) for i in range(function.n_out())]
    for i, c in enumerate(flat):
        buf.set_arg(i, memoryview(c))
    for i, o in enumerate(outs):
        buf.set_res(i, memoryview(o))
    trigger()
    return outs


def ringpair_caller(function: ca.Function, n: int, magnet, columns_per_call: int = 1):
    """points (n, 3) -> B (n, 3) [and G (n, 3, 3)] with ``function`` mapped over n."""
    mapped = function.map(n // columns_per_call, "thread", THREADS)
    centre = np.asarray(magnet.center)
    constants = np.r_[magnet.magnetization, magnet.diameter / 2, magnet.length, magnet.remanence]

    def call(points: np.ndarray) -> list[np.ndarray]:
        const = np.broadcast_to(constants[:, None], (6, n))
        columns = [(points - centre).T, const[:3], const[3:4], const[4:5], const[5:6]]
        outs = evaluate(mapped, columns)
        flux = outs[0].reshape(n, 3)
        if len(outs) == 1:
            return [flux]
        return [flux, outs[1].reshape(n, 3, 3).transpose(0, 2, 1)]

    return call


def best_time(call, points, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = call(points)
        times.append(time.perf_counter() - t0)
    return min(times), result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000, help="field points")
    ap.add_argument("--n-kinds", type=int, default=20_000, help="points per other source kind")
    ap.add_argument("--repeat", type=int, default=7, help="timed runs per method (best kept)")
    args = ap.parse_args()
    n = args.n - args.n % CHUNK

    magnet = default_design().external_magnet
    axis = np.asarray(magnet.magnetization, float)
    rotation = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])[0]
    rng = np.random.default_rng(0)
    points = rotation.apply(outside_points(magnet.diameter, magnet.length, n, rng))
    points += np.asarray(magnet.center)

    cylinder = magpy.magnet.Cylinder(
        polarization=(0, 0, magnet.remanence),
        dimension=(magnet.diameter, magnet.length),
        position=magnet.center,
        orientation=rotation,
    )
    h = 1e-7  # [m] central-difference step for magpylib's gradient

    def magpylib_b(p):
        return [cylinder.getB(p)]

    def magpylib_bg(p):
        grad = np.empty((len(p), 3, 3))
        for j in range(3):
            step = np.zeros(3)
            step[j] = h
            grad[:, :, j] = (cylinder.getB(p + step) - cylinder.getB(p - step)) / (2 * h)
        return [cylinder.getB(p), grad]

    t0 = time.perf_counter()
    compiled_b = compile_function(cylinder_field_function(False))
    compiled_bg = compile_function(cylinder_field_function(True))
    compiled_chunk = compile_function(cylinder_field_function(False).map(CHUNK))
    t_compile = time.perf_counter() - t0
    ours_b = ringpair_caller(compiled_b, n, magnet)
    ours_bg = ringpair_caller(compiled_bg, n, magnet)
    ours_chunk = ringpair_caller(compiled_chunk, n, magnet, CHUNK)

    methods = {
        "ringpair B": ours_b,
        "magpylib B": magpylib_b,
        "ringpair B + G": ours_bg,
        "magpylib B + G (FD)": magpylib_bg,
        "ringpair B, loop in C": ours_chunk,
    }
    for call in methods.values():  # warm up (thread pools, caches)
        call(points[:n])
    best = {name: float("inf") for name in methods}
    results = {}
    for _ in range(args.repeat):  # interleaved, so load changes hit all methods alike
        for name, call in methods.items():
            t, results[name] = best_time(call, points, 1)
            best[name] = min(best[name], t)

    reference = results["magpylib B"][0]
    norm = np.linalg.norm(reference, axis=1)
    rate = {name: n / t for name, t in best.items()}
    print(f"points: {n:,} outside the demonstrator's external magnet, surface to 10 diameters")
    print(
        f"CPUs: {os.cpu_count()}, ringpair threads: {THREADS}; magpylib {magpy.__version__}"
        f" (numpy, one thread); first compilation or cache load {t_compile:.2f} s"
    )
    for name in methods:
        diff = np.linalg.norm(results[name][0] - reference, axis=1) / norm
        print(
            f"{name:22s}: {rate[name] / 1e6:7.3f} M points/s  ({best[name] * 1e3:7.1f} ms;"
            f" max |dB|/|B| vs magpylib {diff.max():.1e})"
        )
    g_ours, g_fd = results["ringpair B + G"][1], results["magpylib B + G (FD)"][1]
    g_diff = np.linalg.norm(g_ours - g_fd, axis=(1, 2)) / np.linalg.norm(g_fd, axis=(1, 2))
    print(
        f"gradient vs magpylib central differences (h = {h:g} m): median relative "
        f"difference {np.median(g_diff):.1e}"
    )
    print(f"ratio B      (ringpair / magpylib): {rate['ringpair B'] / rate['magpylib B']:6.2f} x")
    print(
        f"ratio B + G  (ringpair / magpylib FD): "
        f"{rate['ringpair B + G'] / rate['magpylib B + G (FD)']:6.2f} x"
    )
    print(
        f"ratio B, loop in C (ringpair / magpylib): "
        f"{rate['ringpair B, loop in C'] / rate['magpylib B']:6.2f} x"
    )
    source_kinds(args.n_kinds, args.repeat)


SOURCES = {
    "cuboid": {"dimensions": np.array([0.02, 0.02, 0.01]), "center": np.array([0.2, 0.0, -0.06]),
               "magnetization": np.array([0.0, 0.6, 0.8]), "remanence": 1.3},
    "sphere": {"diameter": 0.02, "center": np.array([0.2, 0.01, -0.05]),
               "magnetization": np.array([1.0, 0.0, 0.0]), "remanence": 1.2},
    "coil": {"radius": 0.05, "turns": 100.0, "current": 2.0, "center": np.array([0.15, 0.0, 0.0]),
             "axis": np.array([0.0, 0.6, 0.8])},
}  # fmt: skip
"""A block magnet 20 x 20 x 10 mm, a 20 mm sphere and a coil of 50 mm radius and 200 A
turns, posed off the base axes. [SI]"""


def magpylib_twin(kind: str, q: dict):
    """magpylib's object of the source (SI: polarization in T, lengths in m, A)."""
    if kind == "cuboid":
        return magpy.magnet.Cuboid(polarization=q["remanence"] * q["magnetization"],
                                   dimension=q["dimensions"], position=q["center"])  # fmt: skip
    if kind == "sphere":
        return magpy.magnet.Sphere(polarization=q["remanence"] * q["magnetization"],
                                   diameter=q["diameter"], position=q["center"])  # fmt: skip
    rotation = Rotation.align_vectors([q["axis"]], [[0.0, 0.0, 1.0]])[0]
    return magpy.current.Circle(current=q["turns"] * q["current"], diameter=2 * q["radius"],
                                position=q["center"], orientation=rotation)  # fmt: skip


def extent(kind: str, q: dict) -> float:
    """The source's largest dimension. [m]"""
    if kind == "cuboid":
        return float(np.linalg.norm(q["dimensions"]))
    return 2 * q["radius"] if kind == "coil" else q["diameter"]


def source_caller(kind: str, q: dict, n: int, gradient: bool):
    """points (n, 3) -> B (n, 3) [and G (n, 3, 3), G[i, j] = dB_i/dp_j] of ``kind``'s
    kernel (exact), compiled and mapped over n as the solver maps its functions."""
    values = np.concatenate([np.ravel(q[k.name]).astype(float) for k in KINDS[kind]])
    prm, p = ca.SX.sym("q", len(values)), ca.SX.sym("p", 3)
    b, g = source_field(kind, split_parameters(kind, prm), p, True, None)
    function = ca.Function(f"{kind}_field", [p, prm], [b, g] if gradient else [b])
    mapped = compile_function(function).map(n, "thread", THREADS)
    constants = np.broadcast_to(values[:, None], (len(values), n))

    def call(points: np.ndarray) -> list[np.ndarray]:
        outs = evaluate(mapped, [points.T, constants])
        flux = outs[0].reshape(n, 3)
        return [flux] if not gradient else [flux, outs[1].reshape(n, 3, 3).transpose(0, 2, 1)]

    return call


def source_kinds(n: int, repeat: int) -> None:
    """Each of :data:`SOURCES` against its magpylib twin: accuracy and throughput ratios."""
    rng = np.random.default_rng(1)
    h = 1e-7  # [m] central-difference step for magpylib's gradient
    print(f"\nother source kinds, {n:,} points from 1.2 to 5 extents around each, exact kernels:")
    for kind, q in SOURCES.items():
        twin = magpylib_twin(kind, q)
        size = extent(kind, q)
        direction = rng.normal(size=(n, 3))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        points = q["center"] + direction * size * rng.uniform(1.2, 5.0, (n, 1))

        def magpylib_b(pts, twin=twin):
            return [twin.getB(pts)]

        def magpylib_bg(pts, twin=twin):
            grad = np.empty((len(pts), 3, 3))
            for j in range(3):
                step = np.zeros(3)
                step[j] = h
                grad[:, :, j] = (twin.getB(pts + step) - twin.getB(pts - step)) / (2 * h)
            return [twin.getB(pts), grad]

        methods = {
            "ringpair B": source_caller(kind, q, n, False),
            "magpylib B": magpylib_b,
            "ringpair B + G": source_caller(kind, q, n, True),
            "magpylib B + G (FD)": magpylib_bg,
        }
        for call in methods.values():  # warm up
            call(points)
        best = {name: float("inf") for name in methods}
        results = {}
        for _ in range(repeat):
            for name, call in methods.items():
                t, results[name] = best_time(call, points, 1)
                best[name] = min(best[name], t)
        reference = results["magpylib B"][0]
        b_diff = np.linalg.norm(results["ringpair B"][0] - reference, axis=1)
        b_diff /= np.linalg.norm(reference, axis=1)
        g_ours, g_fd = results["ringpair B + G"][1], results["magpylib B + G (FD)"][1]
        g_diff = np.linalg.norm(g_ours - g_fd, axis=(1, 2)) / np.linalg.norm(g_fd, axis=(1, 2))
        print(
            f"{kind:7s}: B {best['ringpair B'] * 1e3:6.1f} ms vs magpylib "
            f"{best['magpylib B'] * 1e3:6.1f} ms, ratio "
            f"{best['magpylib B'] / best['ringpair B']:5.2f} x"
            f" (max |dB|/|B| {b_diff.max():.1e}); B + G {best['ringpair B + G'] * 1e3:6.1f} ms vs"
            f" magpylib FD {best['magpylib B + G (FD)'] * 1e3:6.1f} ms, ratio "
            f"{best['magpylib B + G (FD)'] / best['ringpair B + G']:5.2f} x (median |dG|/|G| "
            f"{np.median(g_diff):.1e})"
        )


if __name__ == "__main__":
    main()

"""The field kernels' shared wrapper: a flux density B(offset, ...) written on CasADi
symbols gives its gradient G = dB/dp by CasADi's exact derivative, as a
``casadi.Function`` (called with SX it inlines its graph, with MX it makes a call node,
with numbers it evaluates)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca

FluxDensity = Callable[..., ca.SX]
"""(offset (3,) [m], *parameters) -> B (3,) [T]."""


def field_function(
    name: str, flux: FluxDensity, names: Sequence[str], sizes: Sequence[int], gradient: bool
) -> ca.Function:
    """``flux`` as a Function of symbols of ``sizes`` named ``names`` (the first is the
    offset) -> (B, G = dB/d offset) [T, T/m], G[i, j] = dB_i / dp_j, or B alone without
    ``gradient``."""
    args = [ca.SX.sym(n, k) for n, k in zip(names, sizes, strict=True)]
    b = flux(*args)
    if not gradient:
        return ca.Function(f"{name}_flux_density", args, [b], list(names), ["B"])
    return ca.Function(f"{name}_field", args, [b, ca.jacobian(b, args[0])], list(names), ["B", "G"])

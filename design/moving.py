"""A field source moved as a command beside the ring angles: the classical steering by
moving the magnet, to compare with (and combine with) the ring pair's.

A pose of the moved source is its centre (base frame) and a turn of its magnetisation (a
coil: its axis) about the base z axis from the design's direction; each pose is the design
with that source there (:func:`moved`), checked clear of the straight robot as a design
file is, and the model's parameter vector of each pose becomes one column of the
per-configuration parameters the solvers take (:func:`pose_parameters`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.designfile.checks import check_clearance
from design.designfile.keys import DesignError
from design.model import RingPairModel
from design.records import Design
from design.registry import design_with
from design.units import MM

MOVED_CENTRE = frozenset({"cylinder", "cuboid", "sphere", "coil", "map"})
"""Source kinds that have a centre to move (a map: where its grid's origin lies)."""
TURNED = frozenset({"cylinder", "sphere", "coil"})
"""Source kinds whose pose a turn of the direction describes: an axially magnetised
cylinder's body turns with its magnetisation, a sphere has no sides, a loop's axis is its
pose; a block's sides stay along the base axes (turn it in the design file)."""


@dataclass(frozen=True)
class MovedSource:
    """Which source moves: 0 the ``[external_magnet]``, n ``[[field.sources]]`` number n
    (1-based); ``label`` names it for messages and CSV headers."""

    number: int
    label: str
    kind: str


def moved_source(design: Design, which: str | None) -> MovedSource:
    """The source ``which`` names ('external' or a 1-based source number; None: the
    external magnet where the design has one, else its first source with a centre);
    DesignError naming what the design has where it has no such source."""
    sources = design.sources
    if which is None:
        if design.external_magnet is not None:
            which = "external"
        else:
            movable = [i + 1 for i, s in enumerate(sources) if s.kind in MOVED_CENTRE]
            if not movable:
                raise DesignError(
                    "the design has no field source that can be moved (an external magnet, "
                    f"a cylinder, cuboid, sphere, coil or map); its field: {_kinds(design)}"
                )
            which = str(movable[0])
    if which == "external":
        if design.external_magnet is None:
            raise DesignError(
                f"the design has no [external_magnet] to move; its field: {_kinds(design)}"
            )
        return MovedSource(0, "external_magnet", "cylinder")
    try:
        number = int(which)
    except ValueError:
        number = 0
    if not 1 <= number <= len(sources):
        raise DesignError(
            f"expected 'external' or a field.sources number 1..{len(sources)}; got {which!r}"
        )
    kind = sources[number - 1].kind
    if kind not in MOVED_CENTRE:
        raise DesignError(
            f"field.sources[{number}] is a {kind} source, which has no position to move"
        )
    return MovedSource(number, f"field.sources[{number}]", kind)


def _kinds(design: Design) -> str:
    parts = ["external magnet"] * (design.external_magnet is not None)
    return " + ".join(parts + [s.kind for s in design.sources]) or "none"


def _pose_of(design: Design, source: MovedSource) -> tuple[np.ndarray, np.ndarray]:
    """(centre [m], direction [-]) of ``source`` in ``design``."""
    if source.number == 0:
        ext = design.external_magnet
        assert ext is not None
        return np.array(ext.center), np.array(ext.magnetization)
    src = design.sources[source.number - 1]
    direction = src.axis if src.kind == "coil" else src.magnetization
    return np.array(src.center), np.array(direction)


def moved(design: Design, source: MovedSource, center: np.ndarray, turn: float) -> Design:
    """``design`` with ``source`` centred at ``center`` [m] and its direction turned by
    ``turn`` [rad] about the base z axis; DesignError where the magnet then overlaps the
    straight robot or a block is turned."""
    if turn and source.kind not in TURNED:
        raise DesignError(
            f"{source.label} is a {source.kind}: its pose cannot be turned about z "
            "(a block's sides stay along the base axes; a map's grid too); turn it in the "
            "design file"
        )
    _, direction = _pose_of(design, source)
    c, s = np.cos(turn), np.sin(turn)
    turned = np.array([c * direction[0] - s * direction[1], s * direction[0] + c * direction[1]])
    stem = "external" if source.number == 0 else f"source{source.number}"
    quantity = "axis" if source.kind == "coil" else "magnetization"
    values = {f"{stem}_center_{a}": float(v) for a, v in zip("xyz", center, strict=True)}
    if turn:
        values |= {f"{stem}_{quantity}_{a}": float(v) for a, v in zip("xy", turned, strict=True)}
    out = design_with(design, values)
    try:
        check_clearance(out)
    except DesignError as exc:
        raise DesignError(
            f"{source.label} moved to ({', '.join(f'{v / MM:g}' for v in center)}) mm, turned "
            f"{np.rad2deg(turn):g} deg: {exc}"
        ) from None
    return out


def design_centre(design: Design, source: MovedSource) -> np.ndarray:
    """The centre of ``source`` in ``design`` (base frame). [m]"""
    return _pose_of(design, source)[0]


def pose_parameters(
    model: RingPairModel,
    design: Design,
    source: MovedSource,
    centers: np.ndarray,
    turns: np.ndarray,
) -> np.ndarray:
    """The model's parameters for each pose (``centers`` (N, 3) [m], ``turns`` (N,) [rad]):
    shape (k, N), each distinct pose's design checked once (:func:`moved`)."""
    poses = np.column_stack([centers, turns])
    unique, which = np.unique(poses, axis=0, return_inverse=True)
    columns = np.column_stack(
        [model.parameters(moved(design, source, p[:3], float(p[3]))) for p in unique]
    )
    return columns[:, np.ravel(which)]

"""The moved magnet on the command line: ``--magnet-x``, ``--magnet-y``, ``--magnet-z``,
``--magnet-turn`` and ``--magnet``, taken alike by ``simulate``, ``workspace`` and
``steer`` (the classical steering by moving a field source, beside the rings':
:mod:`design.moving`), and the CSV columns that carry a pose."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import click
import numpy as np

from design.designfile import DesignError
from design.moving import MovedSource, design_centre, moved, moved_source
from design.records import Design
from design.units import MM
from ringpair.options import UserError, angles, bad_input, lengths

MAGNET_COLUMNS = ("magnet_x_mm", "magnet_y_mm", "magnet_z_mm", "magnet_turn_deg")
"""The moved magnet's pose: its centre (base frame) and turn about z from the design's."""
MAGNET_HEADS = dict(
    zip(
        MAGNET_COLUMNS,
        ("magnet x [mm]", "magnet y [mm]", "magnet z [mm]", "turn [deg]"),
        strict=True,
    )
)

_WORDS = dict(
    zip(MAGNET_COLUMNS, ("x {:g} mm", "y {:g} mm", "z {:g} mm", "turned {:g} deg"), strict=True)
)


def pose_words(row: dict, columns: tuple[str, ...]) -> str:
    """The pose ``columns`` of ``row`` (file units) in words: 'magnet y -20 mm, turned 10 deg'."""
    return "magnet " + ", ".join(_WORDS[c].format(row[c]) for c in columns)


_OPTIONS = (
    click.option(
        "--magnet-x",
        default=None,
        help="Move the magnet (the classical steering, beside the rings'): its centre's x "
        "[mm, base frame] as START:STOP:STEP, a comma list or one value; every combination "
        "with the other --magnet-* values is used. Default: the design's.",
    ),
    click.option("--magnet-y", default=None, help="The moved magnet's centre y [mm], same forms."),
    click.option("--magnet-z", default=None, help="The moved magnet's centre z [mm], same forms."),
    click.option(
        "--magnet-turn",
        default=None,
        help="The moved magnet's magnetisation (a coil: its axis) turned about the base z "
        "axis from the design's [deg], same forms. Default: 0.",
    ),
    click.option(
        "--magnet",
        "magnet_source",
        default=None,
        help="Which source the --magnet-* options move: 'external' (the [external_magnet]) "
        "or N (field.sources N, from 1). Default: the external magnet, else the first source "
        "with a position.",
    ),
)


@dataclass(frozen=True)
class MagnetRequest:
    """What was typed for the moved magnet (None: not typed)."""

    x: str | None = None
    y: str | None = None
    z: str | None = None
    turn: str | None = None
    source: str | None = None

    @property
    def given(self) -> bool:
        """Whether any --magnet-* option was typed."""
        return any(v is not None for v in (self.x, self.y, self.z, self.turn, self.source))


@dataclass(frozen=True)
class MagnetPoses:
    """The moved source and its poses (P, 4): centre [m] (base frame) and turn [rad];
    without a moved magnet, ``source`` None and one zero row."""

    source: MovedSource | None
    poses: np.ndarray

    @property
    def moving(self) -> bool:
        return self.source is not None

    def design(self, design: Design, k: int) -> Design:
        """``design`` with the source at pose ``k`` (the design itself when not moving)."""
        if self.source is None:
            return design
        return moved(design, self.source, self.poses[k, :3], float(self.poses[k, 3]))

    def columns(self, k: int) -> dict[str, float]:
        """Pose ``k`` as MAGNET_COLUMNS in file units (mm, deg)."""
        pose = self.poses[k]
        return dict(zip(MAGNET_COLUMNS, [*(pose[:3] / MM), np.rad2deg(pose[3])], strict=True))

    def varied(self) -> tuple[str, ...]:
        """The MAGNET_COLUMNS that differ between poses (the ones worth printing)."""
        return tuple(c for c, v in zip(MAGNET_COLUMNS, self.poses.T, strict=True) if np.ptp(v) > 0)

    def label(self) -> str:
        """'moved magnet: <source> (<kind>)', or '' when not moving."""
        if self.source is None:
            return ""
        return f"moved magnet: {self.source.label} ({self.source.kind})"

    def one(self, command: str) -> MagnetPoses:
        """These poses, refused unless there is one: ``command`` holds the magnet still."""
        if len(self.poses) != 1:
            raise UserError(
                f"{command} holds the magnet at one pose; the --magnet-* values give "
                f"{len(self.poses)} (one value each; `ringpair simulate --magnet-*` sweeps poses)"
            )
        return self


def magnet_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """The --magnet-* options, passed to ``command`` as one ``magnet`` (MagnetRequest)."""

    @functools.wraps(command)
    def wrapper(
        *args: Any,
        magnet_x: str | None,
        magnet_y: str | None,
        magnet_z: str | None,
        magnet_turn: str | None,
        magnet_source: str | None,
        **kwargs: Any,
    ) -> Any:
        typed = MagnetRequest(magnet_x, magnet_y, magnet_z, magnet_turn, magnet_source)
        return command(*args, magnet=typed, **kwargs)

    for option in reversed(_OPTIONS):
        wrapper = option(wrapper)
    return wrapper


def magnet_poses(design: Design, typed: MagnetRequest) -> MagnetPoses:
    """The moved source and every combination of the typed centre coordinates (the
    design's where not typed) and turns; each pose checked as a design file is (the
    magnet clear of the straight robot) before any work."""
    if not typed.given:
        return MagnetPoses(None, np.zeros((1, 4)))
    with bad_input(DesignError):
        source = moved_source(design, typed.source)
    centre = design_centre(design, source) / MM
    values = [
        centre[i : i + 1] if text is None else lengths(text, f"--magnet-{a}")
        for i, (a, text) in enumerate(zip("xyz", (typed.x, typed.y, typed.z), strict=True))
    ]
    turns = np.zeros(1) if typed.turn is None else angles(typed.turn, "--magnet-turn")
    grids = np.meshgrid(*values, turns, indexing="ij")
    return _checked(design, source, np.column_stack([g.ravel() for g in grids]))


def row_poses(design: Design, which: str | None, rows: list[dict], where: str) -> MagnetPoses:
    """One pose per row of a CSV read as dicts, from its MAGNET_COLUMNS present (the
    design's centre and no turn where a column is absent); ``where`` names the file in
    messages, with each row's line."""
    with bad_input(DesignError):
        source = moved_source(design, which)
    default = [*(design_centre(design, source) / MM), 0.0]
    poses = np.empty((len(rows), 4))
    for k, row in enumerate(rows):
        for i, column in enumerate(MAGNET_COLUMNS):
            text = row.get(column)
            try:
                poses[k, i] = default[i] if text is None else float(text)
            except ValueError:
                raise UserError(
                    f"{where} line {k + 2}: {column} expects a number, got {text!r}"
                ) from None
            if not np.isfinite(poses[k, i]):
                raise UserError(f"{where} line {k + 2}: {column} must be finite, got {text!r}")
    return _checked(design, source, poses, where)


def _checked(
    design: Design, source: MovedSource, poses: np.ndarray, where: str | None = None
) -> MagnetPoses:
    """File-unit ``poses`` (P, 4: mm, deg) in SI, each checked clear of the robot."""
    poses = poses.copy()
    poses[:, :3] *= MM
    poses[:, 3] = np.deg2rad(poses[:, 3])
    _, first = np.unique(poses, axis=0, return_index=True)
    for k in np.sort(first):  # each distinct pose once, in the order given
        try:
            moved(design, source, poses[k, :3], float(poses[k, 3]))
        except DesignError as exc:
            raise UserError(f"{where} line {k + 2}: {exc}" if where else str(exc)) from None
    return MagnetPoses(source, poses)

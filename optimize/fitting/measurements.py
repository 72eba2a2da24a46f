"""Measured bench data (docs/formats.md): the CSV, the data-set folder, and their checks.

A measurement is one commanded pair of ring angles with the tip position seen by the
tracker (any of x, y, z; a top view gives x and y only), optionally the ring angles seen
at the tip, the acquisition order and a one-sigma position uncertainty. With the order, a
row may have no position: a configuration the bench drove but did not see (the tracker
lost the tip, or the robot touched the external magnet), which still belongs to the path
the robot was driven along. Files speak
millimetres and degrees; :class:`Measurements` holds SI (m, rad). Every problem with a
file raises :class:`MeasurementError`, whose one message names the file, the line and the
column, what was expected and what was found.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from design.atomic import write_text
from design.designfile import dumps_design, load_design, read_regular
from design.records import Design
from design.suggest import did_you_mean
from design.units import DEG, MM

ANGLE_LIMIT_DEG = 720.0
"""Commanded and tip angles must lie in [-ANGLE_LIMIT_DEG, ANGLE_LIMIT_DEG] (two turns
either way); anything beyond is taken for a unit or typing error. [deg]"""

REQUIRED = ("theta1_deg", "theta2_deg")
POSITION = ("x_mm", "y_mm", "z_mm")
TIP_ANGLES = ("theta1_tip_deg", "theta2_tip_deg")
OPTIONAL = (*POSITION, *TIP_ANGLES, "sequence", "sigma_mm")
COLUMNS = (*REQUIRED, *OPTIONAL)
"""Every column the format knows, in the order files are written."""

DATASET_DESIGN = "design.toml"
DATASET_MEASUREMENTS = "measurements.csv"


class MeasurementError(ValueError):
    """A measured-data file that cannot be used. The message is meant for the user."""


@dataclass(frozen=True)
class Measurements:
    """N measured configurations, SI units.

    command : shape (N, 2), commanded ring angles (theta1 distal, theta2 proximal). [rad]
    position : shape (N, 3), measured tip position, base frame; NaN where not measured
        (all three: a configuration driven but not seen, :attr:`seen`). [m]
    tip_angles : shape (N, 2), measured ring angles at the tip; NaN where not measured. [rad]
    sequence : shape (N,) int, acquisition order, or None when the data do not say.
    sigma : shape (N,), one-sigma position uncertainty of each row; NaN where not given. [m]
    lines : shape (N,) int, line number of each row in its source file (1-based; for data
        made in memory, the row number plus one, as if written with a header).
    source : where the data came from (a path or a description).
    """

    command: np.ndarray
    position: np.ndarray
    tip_angles: np.ndarray
    sequence: np.ndarray | None
    sigma: np.ndarray
    lines: np.ndarray
    source: str = "<memory>"

    def __post_init__(self) -> None:
        n = np.shape(self.command)[0]
        shapes = {
            "command": (np.shape(self.command), (n, 2)),
            "position": (np.shape(self.position), (n, 3)),
            "tip_angles": (np.shape(self.tip_angles), (n, 2)),
            "sigma": (np.shape(self.sigma), (n,)),
            "lines": (np.shape(self.lines), (n,)),
        }
        if self.sequence is not None:
            shapes["sequence"] = (np.shape(self.sequence), (n,))
        for name, (got, want) in shapes.items():
            if got != want:
                raise ValueError(f"Measurements.{name} must have shape {want}; got {got}")

    def __len__(self) -> int:
        return int(np.shape(self.command)[0])

    @property
    def measured(self) -> np.ndarray:
        """shape (N, 3) bool: which position components were measured."""
        return np.isfinite(self.position)

    @property
    def seen(self) -> np.ndarray:
        """shape (N,) bool: rows with a measured position; the others are configurations
        the bench drove along its path but did not see (only with a ``sequence``)."""
        return self.measured.any(axis=1)

    def rows_text(self) -> str:
        """How many rows, and how many of them were not seen: '51 rows (23 not seen)'."""
        lost = int(np.count_nonzero(~self.seen))
        return f"{len(self):,} row{'s' * (len(self) != 1)}" + (
            f" ({lost} not seen)" if lost else ""
        )

    def order(self) -> np.ndarray:
        """Row indices in acquisition order (by ``sequence``; file order without it)."""
        if self.sequence is None:
            return np.arange(len(self))
        return np.argsort(self.sequence, kind="stable")

    def subset(self, rows: np.ndarray | Sequence[int]) -> Measurements:
        """The measurements of ``rows`` (indices or a boolean mask), in that order."""
        idx = np.arange(len(self))[np.asarray(rows)]
        return Measurements(
            command=self.command[idx],
            position=self.position[idx],
            tip_angles=self.tip_angles[idx],
            sequence=None if self.sequence is None else self.sequence[idx],
            sigma=self.sigma[idx],
            lines=self.lines[idx],
            source=self.source,
        )


def make_measurements(
    command: np.ndarray,
    position: np.ndarray,
    *,
    tip_angles: np.ndarray | None = None,
    sequence: np.ndarray | None = None,
    sigma: np.ndarray | None = None,
    source: str = "<memory>",
) -> Measurements:
    """:class:`Measurements` from arrays (SI), with the defaults filled in.

    command : shape (N, 2). [rad]  position : shape (N, 3), NaN where not measured. [m]
    tip_angles : shape (N, 2) or None. [rad]  sequence : shape (N,) or None.
    sigma : shape (N,) or None. [m]
    """
    command = np.asarray(command, float).reshape(-1, 2)
    n = len(command)
    return Measurements(
        command=command,
        position=np.asarray(position, float).reshape(n, 3),
        tip_angles=np.full((n, 2), np.nan)
        if tip_angles is None
        else np.asarray(tip_angles, float).reshape(n, 2),
        sequence=None if sequence is None else np.asarray(sequence, dtype=np.int64).reshape(n),
        sigma=np.full(n, np.nan) if sigma is None else np.asarray(sigma, float).reshape(n),
        lines=np.arange(2, n + 2),
        source=source,
    )


# ---------------------------------------------------------------------------- reading


def load_measurements(path: str | os.PathLike[str]) -> Measurements:
    """Read and check a measured-data CSV (docs/formats.md). [mm, deg] -> SI.

    Raises :class:`MeasurementError` naming the file, line and column on any problem.
    """
    p = Path(path)
    try:
        text = read_regular(p, encoding="utf-8-sig")
    except FileNotFoundError:
        raise MeasurementError(f"measurement file {p} does not exist") from None
    except IsADirectoryError:
        raise MeasurementError(
            f"measurement file {p} is a folder; expected a CSV file "
            f"(a data-set folder is read with its {DATASET_MEASUREMENTS})"
        ) from None
    except UnicodeDecodeError as exc:
        raise MeasurementError(
            f"{p}: expected UTF-8 text; found a byte that is not UTF-8 at offset {exc.start}"
        ) from None
    except OSError as exc:
        raise MeasurementError(f"measurement file {p} cannot be read: {exc}") from None
    return loads_measurements(text, source=str(p))


def loads_measurements(text: str, source: str = "<string>") -> Measurements:
    """Parse and check measured-data CSV text; see :func:`load_measurements`."""
    records: list[tuple[int, list[str]]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if line.lstrip().startswith("#") or not line.strip():
            continue
        try:
            fields = next(csv.reader([line]))
        except csv.Error as exc:  # pragma: no cover - the csv module rarely refuses one line
            raise MeasurementError(f"{source}, line {number}: not valid CSV ({exc})") from None
        records.append((number, [f.strip() for f in fields]))
    if not records:
        raise MeasurementError(
            f"{source} is empty; expected a header row ({', '.join(REQUIRED)}, x_mm, y_mm, "
            "z_mm, ...) and one row per measurement"
        )
    header_line, header = records[0]
    _check_header(source, header_line, header)
    rows = records[1:]
    if not rows:
        raise MeasurementError(
            f"{source} has a header (line {header_line}) but no measurement rows; "
            "expected at least one"
        )
    col = {name: i for i, name in enumerate(header)}
    n = len(rows)
    values = {name: np.full(n, np.nan) for name in COLUMNS if name != "sequence"}
    sequence = np.zeros(n, np.int64) if "sequence" in col else None
    lines = np.array([number for number, _ in rows], dtype=np.int64)
    for k, (number, fields) in enumerate(rows):
        if len(fields) != len(header):
            raise MeasurementError(
                f"{source}, line {number}: expected {len(header)} comma-separated fields "
                f"like the header (line {header_line}); found {len(fields)}"
            )
        where = f"{source}, line {number}"
        for name, i in col.items():
            cell = fields[i]
            if name == "sequence":
                assert sequence is not None
                sequence[k] = _integer(where, name, cell)
            else:
                values[name][k] = _number(where, name, cell, required=name in REQUIRED)
        if sequence is None and not any(np.isfinite(values[c][k]) for c in POSITION):
            given = [c for c in POSITION if c in col]
            raise MeasurementError(
                f"{where}: no tip position; expected a number in at least one of "
                f"{', '.join(given)}; found all empty (a configuration driven but not seen "
                "belongs in a file with a 'sequence' column, which places it on the path)"
            )
    _check_duplicates(source, lines, values, sequence)
    if not np.isfinite(np.column_stack([values[c] for c in POSITION])).any():
        raise MeasurementError(
            f"{source}: no row has a tip position; expected a number in at least one of "
            f"{', '.join(c for c in POSITION if c in col)} in some row"
        )
    return Measurements(
        command=np.column_stack([values["theta1_deg"], values["theta2_deg"]]) * DEG,
        position=np.column_stack([values[c] for c in POSITION]) * MM,
        tip_angles=np.column_stack([values[c] for c in TIP_ANGLES]) * DEG,
        sequence=sequence,
        sigma=values["sigma_mm"] * MM,
        lines=lines,
        source=source,
    )


def _check_header(source: str, line: int, header: list[str]) -> None:
    where = f"{source}, line {line} (header)"
    seen: set[str] = set()
    for name in header:
        if name == "":
            raise MeasurementError(
                f"{where}: a column has no name; expected names from {', '.join(COLUMNS)}"
            )
        if name not in COLUMNS:
            raise MeasurementError(
                f"{where}: unknown column '{name}'{did_you_mean(name, COLUMNS)} "
                f"(expected columns: {', '.join(COLUMNS)})"
            )
        if name in seen:
            raise MeasurementError(f"{where}: column '{name}' appears twice; expected it once")
        seen.add(name)
    missing = [c for c in REQUIRED if c not in seen]
    if missing:
        raise MeasurementError(
            f"{where}: missing required column {', '.join(repr(c) for c in missing)}; "
            f"found columns {', '.join(header)}"
        )
    if not seen & set(POSITION):
        raise MeasurementError(
            f"{where}: missing the tip position; expected at least one of the columns "
            f"{', '.join(POSITION)}; found columns {', '.join(header)}"
        )


def _number(where: str, column: str, cell: str, required: bool) -> float:
    if cell == "":
        if required:
            raise MeasurementError(
                f"{where}, column {column}: expected a number (a required column); found an "
                "empty cell"
            )
        return math.nan
    try:
        x = float(cell)
    except ValueError:
        raise MeasurementError(
            f"{where}, column {column}: expected a number; found {cell!r}"
        ) from None
    if not math.isfinite(x):
        raise MeasurementError(
            f"{where}, column {column}: expected a finite number (leave the cell empty if "
            f"not measured); found {cell!r}"
        )
    if column.startswith("theta") and abs(x) > ANGLE_LIMIT_DEG:
        raise MeasurementError(
            f"{where}, column {column}: expected an angle in degrees within "
            f"[-{ANGLE_LIMIT_DEG:g}, {ANGLE_LIMIT_DEG:g}]; found {cell}"
        )
    if column == "sigma_mm" and x <= 0:
        raise MeasurementError(
            f"{where}, column {column}: expected a positive uncertainty in mm; found {cell}"
        )
    return x


def _integer(where: str, column: str, cell: str) -> int:
    if cell == "":
        raise MeasurementError(
            f"{where}, column {column}: expected an integer (give every row its place in the "
            "acquisition order, or leave the column out); found an empty cell"
        )
    try:
        value = int(cell)
    except ValueError:
        raise MeasurementError(
            f"{where}, column {column}: expected a non-negative integer; found {cell!r}"
        ) from None
    if not 0 <= value <= MAX_SEQUENCE:
        raise MeasurementError(
            f"{where}, column {column}: expected a non-negative integer up to "
            f"{MAX_SEQUENCE:,} (2^63 - 1); found {cell}"
        )
    return value


MAX_SEQUENCE = 2**63 - 1
"""Largest acquisition number a data set may give: what the int64 ``sequence`` holds."""


def _check_duplicates(
    source: str, lines: np.ndarray, values: dict[str, np.ndarray], sequence: np.ndarray | None
) -> None:
    """Same commanded angles and same acquisition (same sequence, or no sequence) twice is
    the same measurement recorded twice; a repeated sequence number is ambiguous order."""
    if sequence is not None:
        first: dict[int, int] = {}
        for k, s in enumerate(sequence):
            if int(s) in first:
                j = first[int(s)]
                same = (
                    values["theta1_deg"][j] == values["theta1_deg"][k]
                    and values["theta2_deg"][j] == values["theta2_deg"][k]
                )
                what = "duplicated row" if same else "repeated sequence number"
                raise MeasurementError(
                    f"{source}: {what}: lines {lines[j]} and {lines[k]} both have sequence "
                    f"{int(s)}"
                    + (
                        f" and the same commanded angles ({values['theta1_deg'][k]:g}, "
                        f"{values['theta2_deg'][k]:g}) deg"
                        if same
                        else ""
                    )
                    + "; expected each acquisition once, with its own sequence number"
                )
            first[int(s)] = k
        return
    seen: dict[tuple[float, float], int] = {}
    for k in range(len(lines)):
        key = (float(values["theta1_deg"][k]), float(values["theta2_deg"][k]))
        if key in seen:
            j = seen[key]
            raise MeasurementError(
                f"{source}: duplicated row: lines {lines[j]} and {lines[k]} both command "
                f"theta1_deg = {key[0]:g}, theta2_deg = {key[1]:g} and there is no sequence "
                "column to tell the acquisitions apart; expected each configuration once, "
                "or a 'sequence' column giving the acquisition order"
            )
        seen[key] = k


def load_dataset(folder: str | os.PathLike[str]) -> tuple[Design, Measurements]:
    """Read a data-set folder: ``design.toml`` (the set-up as built, nominal) and
    ``measurements.csv`` (docs/formats.md). Design-file problems raise
    :class:`~design.designfile.DesignError`, data problems :class:`MeasurementError`."""
    f = Path(folder)
    if not f.exists():
        raise MeasurementError(f"data-set folder {f} does not exist")
    if not f.is_dir():
        raise MeasurementError(
            f"{f} is not a folder; expected a data-set folder with {DATASET_DESIGN} and "
            f"{DATASET_MEASUREMENTS}"
        )
    for name in (DATASET_DESIGN, DATASET_MEASUREMENTS):
        if not (f / name).is_file():
            raise MeasurementError(
                f"data-set folder {f} has no {name}; expected {DATASET_DESIGN} and "
                f"{DATASET_MEASUREMENTS}"
            )
    design = load_design(f / DATASET_DESIGN)
    return design, load_measurements(f / DATASET_MEASUREMENTS)


# ---------------------------------------------------------------------------- writing


def _cell(x: float, scale: float) -> str:
    return "" if not math.isfinite(x) else f"{x / scale:.12g}"


def dumps_measurements(m: Measurements, comment: str | None = None) -> str:
    """CSV text of ``m`` (mm, deg). Optional columns appear only when they hold data.
    ``comment`` lines are written first, each prefixed with '# '."""
    columns = [*REQUIRED, *POSITION]
    if np.isfinite(m.tip_angles).any():
        columns += list(TIP_ANGLES)
    if m.sequence is not None:
        columns.append("sequence")
    if np.isfinite(m.sigma).any():
        columns.append("sigma_mm")
    buf = io.StringIO()
    if comment:
        for line in comment.splitlines():
            buf.write(f"# {line}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for k in range(len(m)):
        cells = {
            "theta1_deg": _cell(m.command[k, 0], DEG),
            "theta2_deg": _cell(m.command[k, 1], DEG),
            "x_mm": _cell(m.position[k, 0], MM),
            "y_mm": _cell(m.position[k, 1], MM),
            "z_mm": _cell(m.position[k, 2], MM),
            "theta1_tip_deg": _cell(m.tip_angles[k, 0], DEG),
            "theta2_tip_deg": _cell(m.tip_angles[k, 1], DEG),
            "sigma_mm": _cell(m.sigma[k], MM),
        }
        if m.sequence is not None:
            cells["sequence"] = str(int(m.sequence[k]))
        writer.writerow([cells[c] for c in columns])
    return buf.getvalue()


def _check_writable(m: Measurements) -> None:
    """Refuse to write data the reader would reject (so a file written is a file read)."""
    text = dumps_measurements(m)
    loads_measurements(text, source="<data to be written>")


def save_measurements(
    path: str | os.PathLike[str], m: Measurements, comment: str | None = None
) -> None:
    """Write ``m`` as a measured-data CSV, atomically. Raises :class:`MeasurementError`
    (and writes nothing) if the data break the format's rules."""
    _check_writable(m)
    write_text(path, dumps_measurements(m, comment))


def save_dataset(
    folder: str | os.PathLike[str],
    design: Design,
    m: Measurements,
    comment: str | None = None,
) -> Path:
    """Write a data-set folder (``design.toml`` + ``measurements.csv``), each file
    atomically, after checking both; returns the folder."""
    _check_writable(m)
    f = Path(folder)
    if f.exists() and not f.is_dir():
        raise MeasurementError(f"{f} exists and is not a folder; expected a data-set folder")
    design_text = dumps_design(design)
    write_text(f / DATASET_MEASUREMENTS, dumps_measurements(m, comment))
    write_text(f / DATASET_DESIGN, design_text)
    return f

"""Hostile-but-fair command lines for the property tests (tests/ringpair/test_fuzz.py) and
the fuzz benchmark (benchmarks/fuzz.py): Hypothesis strategies for design files, study
files, measurement CSVs and option strings, valid, invalid and extreme, and
:func:`run_case`, which runs one through ``ringpair`` in-process and returns what broke
the command line's promises:

- the exit code is 0 or 2, never a traceback;
- on exit 2, nothing in the working folder changed (one message, nothing half-written);
- on exit 0, every pose row is self-consistent (a converged row has its pose, a row
  without a state has empty pose cells), every JSON is strict JSON, no temporary is left;
- nothing is ever written outside the working folder.

Every case runs in a fresh folder (the working directory of the run): inputs in ``in/``,
a file ``afile`` and an empty folder ``adir`` for outputs to collide with.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import io
import json
import math
import os
import stat
import tempfile
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import tomli_w
from click.testing import CliRunner
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
from studies import SMALL

from design.designfile import SECTIONS, default_design, design_to_dict
from ringpair.cli import cli

# Hypothesis caches what it learns (unicode tables, constants) in .hypothesis/ of the working
# directory; keep it out of the checkout, in the system's temporary folder.
set_hypothesis_home_dir(Path(tempfile.gettempdir(), "ringpair-hypothesis"))

DELETE = "<delete>"
"""A mutation's value that removes the key."""

# --- numbers and text ---------------------------------------------------------------------

EXTREME = [0, -1, -0.0, 1e-300, -1e-300, 1e308, -1e308, 1e15, 2**62, math.nan, math.inf, -math.inf]
WRONG_TYPES = ["", "1.0", "half a mm", True, [], [1.0, 2.0], {"a": 1.0}]

extreme_numbers = st.sampled_from(EXTREME)
any_floats = st.floats(allow_nan=True, allow_infinity=True)
wrong_types = st.sampled_from(WRONG_TYPES)
odd_text = st.text(
    st.characters(exclude_categories=("Cs", "Cc")), min_size=0, max_size=24
)  # printable, without NUL: argv cannot carry it


def number_texts() -> st.SearchStrategy[str]:
    """A number as typed: plausible, extreme, or not a number at all."""
    return st.one_of(
        st.integers(-400, 400).map(str),
        st.floats(-400, 400, allow_nan=False).map(lambda x: f"{x:.3g}"),
        st.sampled_from(["inf", "-inf", "nan", "1e308", "-1e308", "1e-300", "0", "-0"]),
        st.sampled_from(["abc", "", " 5 ", "0x10", "1_0", "5deg", "١٢"]),
    )


def angle_texts() -> st.SearchStrategy[str]:
    """--theta1/--theta2 values: one number, a list, a range (either way), or junk."""
    n = number_texts()
    return st.one_of(
        n,
        st.lists(n, min_size=1, max_size=4).map(",".join),
        st.tuples(n, n, n).map(":".join),
        st.tuples(
            st.integers(-180, 180), st.integers(-180, 180), st.sampled_from([1, 5, 30, 90])
        ).map(lambda t: f"{t[0]}:{t[1]}:{t[2]}"),
        st.lists(n, min_size=2, max_size=4).map(":".join),
        odd_text,
    )


def out_paths(kind: str) -> st.SearchStrategy[str]:
    """Where an output option points (relative to the working folder): fresh, nested,
    colliding with a file or a folder, under a file, an input, or an odd name. ``kind`` is
    'file' or 'folder', the suffix of the fresh names."""
    suffix = ".csv" if kind == "file" else ""
    name = st.text(
        st.characters(
            categories=("L", "N", "Zs", "Pd", "Ps", "Pe", "Po"), exclude_characters="/\\:"
        ),
        min_size=1,
        max_size=20,
    ).filter(lambda s: s.strip(". ") != "")
    return st.one_of(
        st.just(f"out/new{suffix}"),
        st.just(f"out/a/b/c{suffix}"),
        st.sampled_from(["adir", "afile", "afile/x", "afile/x/y.csv", "in/design.toml", "."]),
        name.map(lambda s: f"out/{s}{suffix}"),
    )


# --- design files ------------------------------------------------------------------------

NUMERIC_KEYS = [(section, key) for section, keys in SECTIONS.items() for key in keys]


def _plausible(key) -> st.SearchStrategy:
    """A value inside (or at the edge of) a key's range."""
    if key.vector:
        lo = -1000.0 if key.low is None else max(key.low, -1000.0)
        hi = 1000.0 if key.high is None else min(key.high, 1000.0)
        return st.lists(st.floats(lo, hi), min_size=3, max_size=3)
    lo = 0.0 if key.low is None else key.low
    hi = lo + 1000.0 if key.high is None else key.high
    return st.floats(lo, hi)


@st.composite
def design_mutations(draw) -> tuple[str, object]:
    """(dotted key, new value or DELETE) for one edit of a design document."""
    which = draw(st.integers(0, len(NUMERIC_KEYS) + 3))
    if which == len(NUMERIC_KEYS):
        return "name", draw(st.one_of(odd_text, st.sampled_from(["../../escape", "/abs", "[/]"])))
    if which == len(NUMERIC_KEYS) + 1:
        return "external_magnet.shape", draw(st.sampled_from(["cube", "", 1.0]))
    if which == len(NUMERIC_KEYS) + 2:
        return draw(st.sampled_from(["robot.lenght_mm", "tip.colour", "extra"])), 1.0
    if which == len(NUMERIC_KEYS) + 3:
        return draw(st.sampled_from(["robot", "tip", "robot.wire", "environment"])), DELETE
    section, key = NUMERIC_KEYS[which]
    value = draw(
        st.one_of(
            _plausible(key),
            extreme_numbers,
            wrong_types,
            any_floats,
            st.lists(extreme_numbers, min_size=3, max_size=3),
            st.just(DELETE),
        )
    )
    return f"{section}.{key.name}", value


def edited(doc: dict, path: str, value: object) -> dict:
    """``doc`` with ``path`` set to ``value`` (DELETE removes it; missing tables are made)."""
    doc = copy.deepcopy(doc)
    *parents, last = path.split(".")
    node = doc
    for p in parents:
        if not isinstance(node.get(p), dict):
            node[p] = {}
        node = node[p]
    if value == DELETE:
        node.pop(last, None)
    else:
        node[last] = value
    return doc


@st.composite
def design_texts(draw) -> str | bytes:
    """A design file: the demonstrator with up to three edits, or its text cut short, or
    text or bytes that are no TOML at all."""
    base = design_to_dict(default_design())
    kind = draw(st.sampled_from(["edits", "edits", "edits", "cut", "junk", "bytes"]))
    if kind == "edits":
        doc = base
        for path, value in draw(st.lists(design_mutations(), max_size=3)):
            doc = edited(doc, path, value)
        return tomli_w.dumps(doc)
    text = tomli_w.dumps(base)
    if kind == "cut":
        return text[: draw(st.integers(0, len(text)))]
    if kind == "junk":
        return draw(st.text(max_size=200))
    return draw(st.binary(max_size=200))


# --- study files -------------------------------------------------------------------------

STUDY_KEYS = [
    "free.magnet_length_mm",
    "free.magnet_gap_mm",
    "free.wire_outer_diameter_mm",
    "free.external_distance_mm",
    "constraints.twist_limit_deg",
    "constraints.neutral_tolerance_mm",
    "constraints.magnet_clearance_mm",
    "solver.starts",
    "solver.configurations",
    "solver.neutral_configurations",
    "objective",
    "effects",
    "name",
    "materials.catheter",
    "free.unknown_mm",
]


@st.composite
def study_texts(draw, hostile: bool = True) -> str | bytes:
    """A study file: the small test study with one to three edits (``hostile``: at least
    one that no study admits, so the run stays short), or text that is no study."""
    doc = tomllib.loads(SMALL)
    kind = draw(st.sampled_from(["edits", "edits", "edits", "junk"]))
    if kind == "junk":
        return draw(st.one_of(st.text(max_size=200), st.binary(max_size=100)))
    breaking = st.one_of(
        wrong_types,
        st.sampled_from([math.nan, math.inf, -1, 1e308, [5.0, 1.0], [math.nan, 1.0], DELETE]),
    )
    values = breaking if hostile else st.one_of(breaking, st.floats(0, 300), st.integers(1, 3))
    edits = draw(st.lists(st.tuples(st.sampled_from(STUDY_KEYS), values), min_size=1, max_size=3))
    for path, value in edits:
        doc = edited(doc, path, value)
    return tomli_w.dumps(doc)


# --- measurement files -------------------------------------------------------------------

COLUMNS = ["theta1_deg", "theta2_deg", "x_mm", "y_mm", "z_mm", "sequence", "sigma_mm"]


PLAUSIBLE = {
    "theta1_deg": st.floats(-360, 360),
    "theta2_deg": st.floats(-360, 360),
    "x_mm": st.floats(140, 151),
    "y_mm": st.floats(-30, 30),
    "z_mm": st.floats(-30, 30),
    "sequence": st.integers(0, 20),
    "sigma_mm": st.floats(0.01, 2),
}
"""A cell a bench could have measured, by column."""


@st.composite
def csv_texts(draw, max_rows: int = 8) -> str | bytes:
    """A measurement CSV: clean (plausible cells under a usual header), dirty (one cell
    junk or extreme), odd (a shuffled, short or unknown header) or no CSV at all."""
    kind = draw(st.sampled_from(["clean", "clean", "dirty", "odd", "junk"]))
    if kind == "junk":
        return draw(st.one_of(st.text(max_size=200), st.binary(max_size=100)))
    header = draw(
        st.sampled_from([COLUMNS[:5], COLUMNS[:4], COLUMNS, [*COLUMNS[:5], "sigma_mm"]])
        if kind != "odd"
        else st.one_of(
            st.permutations(COLUMNS),
            st.lists(st.sampled_from([*COLUMNS, "junk", ""]), max_size=8),
        )
    )
    cell = {
        c: PLAUSIBLE[c].map(lambda x: f"{x:.6g}") if c in PLAUSIBLE else odd_text for c in header
    }
    rows = [
        list(row)
        for row in draw(st.lists(st.tuples(*[cell[c] for c in header]), max_size=max_rows))
    ]
    if kind == "dirty" and rows and header:
        r, c = draw(st.integers(0, len(rows) - 1)), draw(st.integers(0, len(header) - 1))
        rows[r][c] = draw(number_texts())
    buf = io.StringIO()
    if draw(st.booleans()):
        buf.write("# bench run, fuzzed\n")
    writer = csv.writer(buf, lineterminator=draw(st.sampled_from(["\n", "\r\n"])))
    writer.writerow(header)
    writer.writerows(rows)
    return buf.getvalue()


# --- cases -------------------------------------------------------------------------------


@dataclass
class Case:
    """One command line and the input files it needs (relative to its working folder)."""

    args: list[str]
    files: dict[str, str | bytes] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)
    """Inputs made as one of :data:`KINDS` rather than written."""


FAST = ["--max-configs=60"]
"""Keeps a valid request short: bigger grids are refused (which is exercised too)."""
EFFECTS = st.sampled_from(["none", "default", "", "torsion,twist", "all,none", "gravity"])


@st.composite
def design_cases(draw) -> Case:
    """A design file through ``show`` or ``simulate`` (a few configurations)."""
    files = {"in/design.toml": draw(design_texts())}
    if draw(st.booleans()):
        return Case(["show", "in/design.toml", f"--save={draw(out_paths('file'))}"], files)
    return Case(
        [
            "simulate",
            "in/design.toml",
            "--theta1=0,90",
            "--quiet",
            "--effects=none",
            f"--out={draw(out_paths('file'))}",
            *FAST,
        ],
        files,
    )


@st.composite
def option_cases(draw) -> Case:
    """Option strings for the commands that take angles, steps, seeds and outputs."""
    command = draw(st.sampled_from(["simulate", "simulate", "effects", "workspace", "synth"]))
    if command == "simulate":
        args = [
            f"--theta1={draw(angle_texts())}",
            f"--theta2={draw(angle_texts())}",
            f"--effects={draw(st.sampled_from(['none', 'default', 'torsoin', '']))}",
            f"--out={draw(out_paths('file'))}",
            "--quiet",
            *FAST,
        ]
        if draw(st.booleans()):
            args.append("--ordered")
    elif command == "effects":
        args = [
            f"--theta1={draw(angle_texts())}",
            f"--out={draw(out_paths('file'))}",
            "--max-configs=14",
        ]
    elif command == "workspace":
        step = draw(
            st.one_of(
                st.sampled_from(["45", "90", "0.1", "0", "-5", "nan", "x"]),
                st.floats(30, 90).map(lambda x: f"{x:.4g}"),
            )
        )
        args = [
            f"--step={step}",
            "--effects=none",
            f"--out={draw(out_paths('folder'))}",
            "--max-configs=200",
        ]
    else:
        setting = draw(
            st.one_of(
                st.tuples(
                    st.sampled_from(
                        [
                            "free_length",
                            "wire_torsion_scale",
                            "gravity_z",
                            "external_center_x",
                            "wire_torsion_scal",
                            "tip_mass",
                        ]
                    ),
                    number_texts(),
                ).map("=".join),
                odd_text,
            )
        )
        args = [
            f"--n={draw(st.integers(6, 10))}",
            f"--seed={draw(st.integers(0, 3))}",
            f"--noise-mm={draw(st.sampled_from(['0', '0.3', '-1', 'nan', '1e9']))}",
            f"--set={setting}",
            f"--out={draw(out_paths('folder'))}",
        ]
    return Case([command, *args])


@st.composite
def data_cases(draw) -> Case:
    """A measurement CSV through ``calibrate`` or (too few rows to run long) ``diagnose``."""
    command = draw(st.sampled_from(["calibrate", "calibrate", "diagnose"]))
    files = {"in/data.csv": draw(csv_texts(max_rows=8 if command == "calibrate" else 4))}
    args = [command, "in/data.csv"]
    if draw(st.sampled_from([False, False, False, True])):
        files["in/design.toml"] = draw(design_texts())
        args.append("--design=in/design.toml")
    args.append(f"--json={draw(out_paths('file'))}")
    if command == "diagnose" and draw(st.booleans()):
        args.append(f"--folds={draw(st.sampled_from(['1', '2', '3', '0', 'x']))}")
    return Case(args, files)


@st.composite
def study_cases(draw, hostile: bool = True) -> Case:
    """A study file through ``optimize`` (without the Pareto sweeps)."""
    files = {"in/study.toml": draw(study_texts(hostile))}
    return Case(
        ["optimize", "in/study.toml", "--no-pareto", f"--out={draw(out_paths('folder'))}"], files
    )


# --- file kinds, nesting, integer extremes, degenerate designs ----------------------------

BIG_INTEGERS = [2**63, -(2**63) - 1, 2**64, 10**20, 12345678901234567890, 10**400, -(10**400)]
"""Integers TOML holds and neither int64 nor a float does."""
KINDS = ["fifo", "folder", "dangling link", "empty", "link to a file"]
"""What an input path may be other than a regular file with content (:func:`run_case`)."""
DEGENERATE = [
    ("robot.free_length_mm", [0.5, 4.3, 4.35, 4.36, 4.4, 5.0]),  # the rigid offset, 4.35 mm
    ("robot.catheter.youngs_modulus_mpa", [1e-6, 1e-3]),
    ("robot.wire.youngs_modulus_mpa", [1e-6, 1e-3]),
    ("tip.remanence_t", [0.0, 1e-12]),
    ("tip.magnet_length_mm", [1e-300, 0.001, 0.02, 100.0]),
    ("tip.gap_mm", [0.0, 1e-300, 100.0]),
    ("external_magnet.remanence_t", [0.0, 1.6]),
    ("external_magnet.center_mm", [[10000.0, 0.0, 0.0], [200.0, 0.0, 0.0], [0.0, 0.0, 150.0]]),
    ("external_magnet.diameter_mm", [1e-300, 10000.0]),
]
"""Corners of the design space: a rod about as long as the printed tip's rigid offset, a
rod softer than rubber, rings with no moment or no length, a magnet far or at the side."""


@st.composite
def nested_texts(draw) -> str:
    """TOML nested ``depth`` deep: arrays, inline tables or a dotted table header."""
    depth = draw(st.sampled_from([2, 50, 1000, 100_000]))
    form = draw(st.sampled_from(["array", "table", "header"]))
    if form == "array":
        return "x = " + "[" * depth + "]" * depth + "\n"
    if form == "table":
        return "x = " + "{a = " * depth + "1" + "}" * depth + "\n"
    return "[" + ".".join(["a"] * min(depth, 5000)) + "]\nb = 1\n"


@st.composite
def degenerate_design_texts(draw) -> str:
    """The demonstrator at one to three corners of :data:`DEGENERATE`, or with a numeric key
    set to an integer of :data:`BIG_INTEGERS`."""
    doc = design_to_dict(default_design())
    for path, values in draw(st.lists(st.sampled_from(DEGENERATE), min_size=1, max_size=3)):
        doc = edited(doc, path, draw(st.sampled_from(values)))
    if draw(st.booleans()):
        section, key = draw(st.sampled_from(NUMERIC_KEYS))
        big = draw(st.sampled_from(BIG_INTEGERS))
        doc = edited(doc, f"{section}.{key.name}", [big, 0, 0] if key.vector else big)
    return tomli_w.dumps(doc)


@st.composite
def input_cases(draw) -> Case:
    """Inputs no ordinary file gives: a design, study or data path that is a FIFO, a
    folder, a dangling link or empty; TOML nested deep; integers beyond int64 and float in
    design, study and data files and options; designs at the corners of the design space,
    through show, simulate, workspace, calibrate and optimize."""
    family = draw(st.sampled_from(["kind", "nested", "integers", "degenerate", "degenerate"]))
    if family == "kind":
        command = draw(st.sampled_from(["show", "simulate", "calibrate", "optimize"]))
        name = {"calibrate": "in/data.csv", "optimize": "in/study.toml"}.get(
            command, "in/design.toml"
        )
        args = {
            "show": ["show", name],
            "simulate": ["simulate", name, "--theta1=0", "--effects=none", "--out=out/s.csv"],
            "calibrate": ["calibrate", name, "--json=out/f.json"],
            "optimize": ["optimize", name, "--no-pareto", "--out=out/o"],
        }[command]
        return Case(args, kinds={name: draw(st.sampled_from(KINDS))})
    if family == "nested":
        command = draw(st.sampled_from(["show", "optimize"]))
        name = "in/design.toml" if command == "show" else "in/study.toml"
        args = [command, name] + (["--no-pareto", "--out=out/o"] if command == "optimize" else [])
        return Case(args, {name: draw(nested_texts())})
    if family == "integers":
        big = str(draw(st.sampled_from(BIG_INTEGERS)))
        choice = draw(st.sampled_from(["sequence", "study", "seed", "n", "samples"]))
        if choice == "sequence":
            text = f"{','.join(COLUMNS[:6])}\n0,0,150,1,1,0\n90,0,150,2,1,{big}\n"
            return Case(["calibrate", "in/data.csv", "--json=out/f.json"], {"in/data.csv": text})
        if choice == "study":
            doc = edited(tomllib.loads(SMALL), draw(st.sampled_from(STUDY_KEYS)), int(big))
            return Case(
                ["optimize", "in/study.toml", "--no-pareto", "--out=out/o"],
                {"in/study.toml": tomli_w.dumps(doc)},
            )
        option = {"seed": "synth", "n": "synth", "samples": "study"}[choice]
        return Case([option, f"--{choice}={big}", "--out=out/x"])
    text = draw(degenerate_design_texts())
    command = draw(st.sampled_from(["show", "simulate", "simulate", "workspace"]))
    args = {
        "show": ["show", "in/design.toml"],
        "simulate": [
            "simulate",
            "in/design.toml",
            "--theta1=0,90,180",
            f"--effects={draw(st.sampled_from(['none', 'default']))}",
            "--quiet",
            "--out=out/s.csv",
            *FAST,
        ],
        "workspace": ["workspace", "in/design.toml", "--step=90", "--effects=none", "--out=out/w"],
    }[command]
    return Case(args, {"in/design.toml": text})


# --- running a case ----------------------------------------------------------------------


@dataclass
class Outcome:
    """What a case did: its exit code, output, and the promises it broke (empty: none)."""

    exit_code: int
    output: str
    problems: list[str]


def _snapshot(folder: Path) -> dict[str, str]:
    """Every file and folder below ``folder`` -> a hash of its content ('dir' for folders)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        key = str(p.relative_to(folder))
        info = p.lstat()
        if stat.S_ISDIR(info.st_mode):
            out[key] = "dir"
        elif stat.S_ISREG(info.st_mode):
            out[key] = hashlib.sha256(p.read_bytes()).hexdigest()
        else:  # a FIFO or a link: never opened (a FIFO would block)
            out[key] = (
                f"special {stat.S_IFMT(info.st_mode)} {os.readlink(p) if p.is_symlink() else ''}"
            )
    return out


def _make(path: Path, kind: str) -> None:
    """An input of :data:`KINDS` at ``path``."""
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    elif kind == "dangling link":
        path.symlink_to(path.with_name("nothing-here"))
    elif kind == "empty":
        path.write_text("")
    else:
        path.with_name("target").write_text("x = 1\n")
        path.symlink_to("target")


def _strict_json(text: str) -> None:
    def refuse(name: str) -> None:
        raise ValueError(f"not JSON: {name}")

    json.loads(text, parse_constant=refuse)


def _pose_problems(path: Path) -> list[str]:
    """Rows of a pose CSV that contradict themselves."""
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    problems = []
    for k, row in enumerate(csv.DictReader(lines)):
        if "converged" not in row:
            return []
        pose = [row[c] for c in ("x_mm", "y_mm", "z_mm", "tangent_x", "deflection_mm")]
        if row["converged"] == "true" and "" in pose:
            problems.append(f"{path.name} row {k + 1}: converged=true without a pose")
        if row["converged"] == "false" and any(pose):
            problems.append(f"{path.name} row {k + 1}: no state, yet pose cells")
        if row["converged"] == "false" and not row["failure"]:
            problems.append(f"{path.name} row {k + 1}: no state and no reason")
    return problems


def run_case(case: Case) -> Outcome:
    """Run ``case`` in a fresh folder and check the command line's promises."""
    with tempfile.TemporaryDirectory() as root:
        work = Path(root, "work")
        (work / "in").mkdir(parents=True)
        (work / "adir").mkdir()
        (work / "afile").write_text("someone's file\n")
        for name, content in case.files.items():
            path = work / name
            path.write_bytes(content if isinstance(content, bytes) else content.encode())
        for name, kind in case.kinds.items():
            _make(work / name, kind)
        before = _snapshot(work)
        here = os.getcwd()
        os.chdir(work)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a numerical warning is not a broken promise
                result = CliRunner().invoke(cli, case.args)
        finally:
            os.chdir(here)
        problems = []
        output = result.output
        if result.exit_code not in (0, 2):
            problems.append(f"exit code {result.exit_code}")
        if result.exception is not None and not isinstance(result.exception, SystemExit):
            problems.append(f"{type(result.exception).__name__}: {result.exception}")
        if "Traceback" in output:
            problems.append("a traceback in the output")
        if sorted(os.listdir(root)) != ["work"]:
            problems.append(f"wrote outside its folder: {sorted(os.listdir(root))}")
        after = _snapshot(work)
        if result.exit_code == 2 and after != before:
            changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
            problems.append(f"exit 2, yet changed: {changed[:5]}")
        if result.exit_code == 0:
            for key, digest in after.items():
                path = work / key
                if key.endswith(".tmp"):
                    problems.append(f"a temporary left: {key}")
                elif before.get(key) == digest or digest == "dir":
                    continue
                elif path.suffix == ".csv":
                    problems += _pose_problems(path)
                elif path.suffix == ".json":
                    try:
                        _strict_json(path.read_text())
                    except ValueError as exc:
                        problems.append(f"{key}: {exc}")
        return Outcome(result.exit_code, output, problems)

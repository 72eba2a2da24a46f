"""Bench data sets with planted effects, drawn across the whole design space.

For the diagnosis benchmark (``benchmarks/diagnose.py``) and its tests: each data set is
a nominal design file drawn by :func:`optimize.fitting.setups.random_design`, a robot as
built that differs from it, the planted effects at random strengths, and a bench run of
that truth (:func:`optimize.fitting.synth.synthesize_data`) with tracker noise. On
request (``on_axis``) the nominal design has its magnet on the robot's axis, magnetised
along it, as in the paper's set-up (:func:`optimize.fitting.setups.on_axis`).

As built (drawn for every data set, null ones too): each tube's Young's modulus within
+-30 % of the file's (bending and twisting stiffness alike), each magnet's remanence
within +-10 %, the external magnet's centre within +-3 mm of the file's on each axis.
The bench: 16-80 commanded configurations on the bench path of
:func:`optimize.fitting.synth.default_commands`, a 3-D or a top view, noise 0.1-0.5 mm
per coordinate, with or without the acquisition order (``sequence``; always with it
where hysteresis is planted; without it the sweeps go one way, each configuration once,
as a data set without the order must), with or without each row's sigma. Every drawn set
can be written as a data-set folder (:func:`optimize.fitting.measurements.save_dataset`).

Planted strengths: transmissions 0.3-3 x their nominal torsional rigidity
(log-uniform), friction play 2-8 deg in each transmission, a tip mass of 0-0.5 g with the
rods' own weight (gravity along the file's direction, drawn where the file has none); the
exact field and the rod's nonlinearity come with the geometry (for a planted
``near_field`` the magnet's face is drawn 8-30 mm from the tip).

**Detectability criterion.** A planted effect can only be named if the other models
cannot absorb it. For each planted effect, the model with every other planted effect
(the calibrated baseline for a single effect) is fitted to the noise-free data with the
diagnosis' own fits (its default free parameters, started from the nominal design and
from the truth); the effect's *margin* is that fit's RMS residual per measured
coordinate over the noise. A data set is detectable where every planted effect's margin
is at least DETECTABLE. The margins' fits have no priors (the other models may absorb
what they can anywhere within their bounds): the diagnosis, which fits with priors, can
absorb less, so a set detectable by this criterion is detectable by it (and the drawn
sets are those drawn before priors). :func:`draw_planted` redraws a set-up (at most ``tries`` times)
until it is detectable and says so when it is not.

SI units inside; ``noise_mm`` is millimetres.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass

import numpy as np

from design.records import Design
from design.units import DEG, MM
from optimize.fitting.diagnose import DETECTABLE, _fit
from optimize.fitting.measurements import Measurements
from optimize.fitting.setups import FACE_MM, random_design
from optimize.fitting.setups import on_axis as put_on_axis
from optimize.fitting.synth import VIEWS, Synthetic, synthesize_data

PLANTABLE = ("near_field", "large_deflection", "torsion", "gravity", "hysteresis")
"""The effects the diagnosis names (docs/formats.md)."""
PLANTED_SETS: tuple[frozenset[str], ...] = (
    frozenset(),
    *(frozenset({e}) for e in PLANTABLE),
    *(frozenset(p) for p in itertools.combinations(PLANTABLE, 2)),
)
"""What the benchmark plants: nothing (the null sets), each effect, each pair."""
POINTS = (16, 80)
"""Range of commanded configurations of a data set."""
NOISE_MM = (0.1, 0.5)
"""Range of the tracker's one-sigma noise per coordinate. [mm]"""
NEAR_FACE_MM = (FACE_MM[0], 30.0)
"""Face distance of the external magnet where ``near_field`` is planted. [mm]"""
MIN_ROWS = 12
"""A draw whose bench run keeps fewer stable configurations is drawn again."""


@dataclass(frozen=True)
class Planted:
    """A drawn bench data set and how it was made.

    design : the nominal design file the diagnosis is given.
    planted : the effects of the truth.
    truth : the as-built parameters and the effects' own (names of
        :data:`design.registry.NAMES`). [SI]
    synthetic : the bench run (its ``measurements`` are the noisy data).
    noise_mm : one-sigma noise per coordinate. [mm]
    view, ordered, stated_sigma : 3-D or top view; with ``sequence``; with ``sigma_mm``.
    margin : per planted effect, the detectability margin (module docstring). [-]
    tries : draws it took.
    on_axis : the nominal design has its magnet on the robot's axis
        (:func:`optimize.fitting.setups.on_axis`; as built it is off by the offsets).
    """

    design: Design
    planted: frozenset[str]
    truth: dict[str, float]
    synthetic: Synthetic
    noise_mm: float
    view: str
    ordered: bool
    stated_sigma: bool
    margin: dict[str, float]
    tries: int
    on_axis: bool = False

    @property
    def measurements(self) -> Measurements:
        return self.synthetic.measurements

    @property
    def detectable(self) -> bool:
        """Every planted effect's margin reaches DETECTABLE (true for null sets)."""
        return all(v >= DETECTABLE for v in self.margin.values())

    @property
    def name(self) -> str:
        return "+".join(sorted(self.planted)) or "null"

    def describe(self) -> str:
        """One line: what was planted, how it was measured, its margins."""
        d = self.design
        margins = ", ".join(f"{k} {v:.2g}" for k, v in sorted(self.margin.items()))
        return (
            f"{self.name}: L {d.robot.free_length / MM:.0f} mm, "
            + ("magnet on axis, " if self.on_axis else "")
            + f"{self.measurements.rows_text()}, {self.view}, "
            f"{'sequence' if self.ordered else 'no sequence'}, noise {self.noise_mm:.2f} mm"
            + (f", margin {margins}" if margins else "")
        )


def as_built(rng: np.random.Generator, design: Design) -> dict[str, float]:
    """The robot as built: its differences from ``design`` (module docstring). [SI]"""
    em = design.external_magnet
    truth = {
        "catheter_youngs_modulus": design.robot.catheter.youngs_modulus * rng.uniform(0.7, 1.3),
        "wire_youngs_modulus": design.robot.wire.youngs_modulus * rng.uniform(0.7, 1.3),
        "magnet_remanence": design.tip.magnet_remanence * rng.uniform(0.9, 1.1),
        "external_remanence": em.remanence * rng.uniform(0.9, 1.1),
    }
    for axis, centre in zip("xyz", em.center, strict=True):
        truth[f"external_center_{axis}"] = centre + rng.uniform(-3.0, 3.0) * MM
    return truth


def effect_strengths(rng: np.random.Generator, planted: frozenset[str]) -> dict[str, float]:
    """The planted effects' own parameters (module docstring). [SI]"""
    out: dict[str, float] = {}
    if "torsion" in planted:
        for name in ("wire_torsion_scale", "catheter_torsion_scale"):
            out[name] = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
    if "hysteresis" in planted:
        for name in ("wire_friction_angle", "catheter_friction_angle"):
            out[name] = rng.uniform(2.0, 8.0) * DEG
    if "gravity" in planted:
        out["tip_mass"] = rng.uniform(0.0, 0.5e-3)
    return out


def margins(case: Planted) -> dict[str, float]:
    """Each planted effect's detectability margin (module docstring): the RMS residual per
    measured coordinate, over the noise, of the model without it fitted to the noise-free
    data; infinite where that model cannot solve every row. [-]"""
    m = case.synthetic.noise_free
    out = {}
    for effect in sorted(case.planted):
        fit = _fit(
            case.design,
            m,
            case.planted - {effect},
            k=2,
            seed=0,
            cv=False,
            starts=[None, case.truth],
            sigma=None,
            priors=False,
        )
        out[effect] = math.sqrt(fit.rss / fit.n) / (case.noise_mm * MM)
    return out


def draw_planted(
    rng: np.random.Generator,
    planted: frozenset[str],
    tries: int = 6,
    points: tuple[int, int] = POINTS,
    on_axis: bool = False,
) -> Planted:
    """A bench data set with ``planted`` effects (module docstring), drawn again until it
    is detectable, at most ``tries`` times (the last draw is returned either way).
    ``points``: the range of commanded configurations, within POINTS. ``on_axis``: the
    nominal design's magnet on the robot's axis (:func:`optimize.fitting.setups.on_axis`)."""
    case = None
    for attempt in range(1, tries + 1):
        face = NEAR_FACE_MM if "near_field" in planted else FACE_MM
        design = random_design(rng, face_mm=face)
        if on_axis:
            design = put_on_axis(rng, design, face)
        if "gravity" in planted and design.environment.gravity is None:
            g = rng.normal(size=3)
            gravity = tuple(9.81 * g / np.linalg.norm(g))
            design = dataclasses.replace(
                design, environment=dataclasses.replace(design.environment, gravity=gravity)
            )
        truth = {**as_built(rng, design), **effect_strengths(rng, planted)}
        noise = rng.uniform(*NOISE_MM)
        view = str(rng.choice(VIEWS))
        ordered = "hysteresis" in planted or bool(rng.random() < 0.5)
        stated = bool(rng.random() < 0.5)
        synthetic = synthesize_data(
            design,
            planted,
            n=int(rng.integers(points[0], points[1] + 1)),
            view=view,
            noise_mm=noise,
            seed=int(rng.integers(2**31)),
            params_override=truth,
            record_sigma=stated,
            ordered=ordered,
        )
        if synthetic.measurements.seen.sum() < MIN_ROWS:
            continue
        case = Planted(
            design, planted, truth, synthetic, noise, view, ordered, stated, {}, attempt, on_axis
        )
        case = dataclasses.replace(case, margin=margins(case))
        if case.detectable:
            return case
    if case is None:
        raise RuntimeError(
            f"no bench run of {sorted(planted)} kept {MIN_ROWS} rows in {tries} draws"
        )
    return case


__all__ = ["DETECTABLE", "PLANTED_SETS", "Planted", "as_built", "draw_planted", "margins"]

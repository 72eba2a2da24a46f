"""Priors: what a bench knows about each free parameter before it measures.

Every parameter calibration can free has a stated one-sigma uncertainty about its nominal
value (the design file's, or 1 for a model factor), in its fit units
(:data:`optimize.fitting.calibrate.policy.FREE_PARAMETERS`): by default the registry's
(:class:`design.registry.FitSpec` ``prior``), which is at least the manufacturing or placement
tolerance of :mod:`design.registry` and covers what a bench does not control:

- the external magnet's centre, 5 mm per axis (placed to +-1 mm by the registry's
  tolerance, but a bench measures it from a fixture, not at the magnet's centre);
- the tubes' Young's moduli and the rod's bending-rigidity factor, a factor e^0.5 = 1.65
  one sigma (extruded tubes spread 10 %, and the paper's "compound" modulus could not be
  pinned down); the torsion factors a factor e = 2.7;
- the remanences, 10 % (grades spread 2 %; a magnet's field also falls with its
  temperature and age); the free length, 5 mm; friction play, 5 deg; the tip's extra
  mass, 1 g; the magnetisation direction, 0.05 per component.

A calibration with priors maximises the posterior: one Gaussian residual
(u - u_nominal) / width per free parameter is appended to the weighted data residuals
(:func:`optimize.fitting.calibrate.calibrate`). Each estimate's *pull* is how many prior
sigmas it moved, (u - u_nominal) / width; a fit that needs one beyond PULL_LIMIT is not
physical, and a model that needs it does not explain the data. A least-squares fit
*needs* it only where the data pin the estimate away from nominal (:func:`conflict`, the
prior-data conflict, beyond PULL_LIMIT too); an estimate that wandered beyond along a
direction the data leave free is not needed there.

Overrides, by key: a linearly fitted parameter's one sigma in its file unit with the
unit's suffix (``external_center_x_mm = 3``; a vector's key without the axis sets all
three, ``external_center_mm = 3``); a parameter fitted on a log scale (moduli,
remanences, scale factors) takes the one sigma of ln(value / nominal), about the relative
one, without a suffix (``bending_rigidity_scale = 0.3``); ``inf`` drops that prior. They
are read from a data-set folder's ``priors.toml`` (:data:`PRIORS_FILE`) and from the
command line (``--prior external_center_mm=3``), which wins. SI units inside.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from design.registry import FILE_UNITS, PARAMETERS
from optimize.fitting.calibrate.policy import FREE_PARAMETERS

PULL_LIMIT = 3.0
"""An estimate more than this many prior sigmas from its nominal value is not physical:
the fit that needs it says so, and its model does not explain the data. [-]"""
PRIORS_FILE = "priors.toml"
"""The file of a data-set folder that overrides the default priors (module docstring)."""

Priors = Mapping[str, float]
"""Prior widths by free parameter, in fit units (log: of ln(value / nominal)); infinite:
no prior. [fit units]"""


def prior_widths(overrides: Priors | None = None) -> dict[str, float]:
    """The one-sigma prior width of every free parameter in fit units: the registry's
    default, or ``overrides``' (fit units, as :func:`parse_priors` gives them)."""
    widths = {n: float(spec.prior) for n, spec in FREE_PARAMETERS.items()}
    for name, width in (overrides or {}).items():
        if name not in widths:
            raise ValueError(f"prior for {name!r}, which calibration cannot free")
        widths[name] = float(width)
    return widths


def _names_of(key: str) -> tuple[list[str], str]:
    """The free parameters a prior's key sets, and the unit suffix it carries."""
    if key in FREE_PARAMETERS:
        return [key], ""
    for suffix in sorted({s for _, _, s in FILE_UNITS.values() if s}, key=len, reverse=True):
        if key.endswith("_" + suffix):
            base = key[: -len(suffix) - 1]
            if base in FREE_PARAMETERS:
                return [base], suffix
            axes = [f"{base}_{a}" for a in "xyz"]
            if all(a in FREE_PARAMETERS for a in axes):
                return axes, suffix
    axes = [f"{key}_{a}" for a in "xyz"]
    if all(a in FREE_PARAMETERS for a in axes):
        return axes, ""
    return [], ""


def _expected(name: str) -> str:
    """How a prior of ``name`` is written."""
    spec = FREE_PARAMETERS[name]
    if spec.kind == "log":
        return f"{name} = <one sigma of ln(value / nominal)>"
    unit, size, suffix = FILE_UNITS.get(PARAMETERS[name].unit, ("", 1.0, ""))
    return f"{name}_{suffix} = <one sigma in {unit}>" if suffix else f"{name} = <one sigma>"


def parse_priors(items: Mapping[str, object], where: str = "prior") -> dict[str, float]:
    """Prior overrides by key (module docstring) as widths in fit units by free
    parameter. A key no free parameter has, a unit suffix where none is expected (or none
    where one is), or a width that is not a positive number (or ``inf``) is a ValueError
    naming ``where`` and the key."""
    out: dict[str, float] = {}
    for key, raw in items.items():
        names, suffix = _names_of(key)
        if not names:
            raise ValueError(
                f"{where}: {key!r} is no parameter calibration can free; expected keys like "
                "external_center_mm, external_center_x_mm, bending_rigidity_scale, "
                f"free_length_mm (parameters: {', '.join(FREE_PARAMETERS)})"
            )
        try:
            value = float(raw)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            value = math.nan
        if not value > 0:
            raise ValueError(
                f"{where}: {key} must be a positive one-sigma width (or inf: no prior); got {raw!r}"
            )
        for name in names:
            spec = FREE_PARAMETERS[name]
            unit_suffix = FILE_UNITS.get(PARAMETERS[name].unit, ("", 1.0, ""))[2]
            wants = "" if spec.kind == "log" else unit_suffix
            if suffix != wants:
                raise ValueError(f"{where}: {key!r}: expected {_expected(name)}")
            if spec.kind == "log":
                out[name] = value
            else:
                size = FILE_UNITS.get(PARAMETERS[name].unit, ("", 1.0, ""))[1]
                out[name] = value * size / spec.step
    return out


def parse_prior_options(texts: Iterable[str]) -> dict[str, float]:
    """``--prior KEY=SIGMA`` options (module docstring) as :func:`parse_priors` gives
    them; a text without '=' is a ValueError."""
    items: dict[str, object] = {}
    for text in texts:
        key, sep, value = text.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--prior {text!r}: expected KEY=SIGMA, e.g. external_center_mm=3")
        items[key.strip()] = value.strip()
    return parse_priors(items, "--prior")


def load_priors(folder: str | Path) -> dict[str, float]:
    """The overrides of a data-set folder's PRIORS_FILE (none if it has none)."""
    path = Path(folder) / PRIORS_FILE
    if not path.is_file():
        return {}
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a TOML file ({exc})") from None
    items = doc.get("priors", doc)
    if not isinstance(items, dict):
        raise ValueError(f"{path}: expected KEY = SIGMA lines (or a [priors] table)")
    return parse_priors(items, str(path))


def pull(name: str, value: float, nominal: float, width: float) -> float:
    """How many prior sigmas ``value`` lies from ``nominal`` (signed; 0 without a
    prior: an infinite ``width``). [-]"""
    if not math.isfinite(width):
        return 0.0
    return FREE_PARAMETERS[name].fit_unit(value, nominal) / width


def conflict(offset: np.ndarray, width: np.ndarray, data_covariance: np.ndarray) -> float:
    """How far a least-squares estimate lies from the nominal design once the priors'
    and the data's own uncertainty are both counted: the prior-data conflict
    sqrt(d^T (W + S)^-1 d), d the estimate's offset from nominal, W the priors' and S the
    data's covariance (all in fit units). It is the largest pull of any combination of the
    parameters, a^T d / sqrt(a^T (W + S) a) over all a, and for one parameter
    d / sqrt(w^2 + s^2): where the bench is as its priors say, the truth lies about
    nominal with W and the estimate about the truth with S (linear Gaussian). Its square
    is the misfit a fit at the priors' centre adds to the least-squares one, to first
    order. An estimate that wandered far along a direction the data leave free (a far
    magnet's distance traded against the rod's stiffness) is in no conflict; one the data
    pin there, even through parameters that trade off, is. Parameters without a prior
    (infinite width) or that the data do not determine (non-finite variance) are left
    out; 0 where none is left. [-]"""
    d, w, cov = (np.asarray(a, dtype=float) for a in (offset, width, data_covariance))
    keep = np.isfinite(w) & np.isfinite(d) & np.isfinite(np.diag(cov))
    cov = np.nan_to_num(cov[np.ix_(keep, keep)], nan=0.0)  # an undetermined one's NaNs
    if not keep.any():
        return 0.0
    d = d[keep]
    return math.sqrt(max(float(d @ np.linalg.solve(np.diag(w[keep] ** 2) + cov, d)), 0.0))


def prior_sigma_shown(name: str, width: float) -> float:
    """A prior width in report units: for a linearly fitted parameter in its report
    unit (mm, deg, g), for a log-fitted one the one sigma of ln(value / nominal). [-]"""
    spec = FREE_PARAMETERS[name]
    if spec.kind == "log":
        return width
    return width * spec.step * spec.label[1]


__all__ = [
    "PRIORS_FILE",
    "PULL_LIMIT",
    "Priors",
    "conflict",
    "load_priors",
    "parse_prior_options",
    "parse_priors",
    "prior_sigma_shown",
    "prior_widths",
    "pull",
]

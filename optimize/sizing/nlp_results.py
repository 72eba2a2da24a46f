"""What a design study returns: each constraint group's state at a solution, conflicts
between constraints, each start's outcome, the study's result and a single design's
evaluation. SI units unless a field says otherwise."""

from __future__ import annotations

from dataclasses import dataclass, field

from design.records import Design


@dataclass(frozen=True)
class ConstraintState:
    """One constraint group at a solution (its worst row).

    value, limit : SI (m, rad, -, m^3); the group's ``unit`` and ``scale`` (SI per unit)
        convert them for reports. ``limit`` is the bound that binds first.
    margin : distance to the limit, positive inside. [SI]
    active : at its limit (within ACTIVE_TOLERANCE) or with a nonzero multiplier.
    multiplier : largest |Lagrange multiplier| of the group's rows (scaled problem).
    """

    name: str
    value: float
    limit: float
    margin: float
    active: bool
    multiplier: float
    unit: str
    scale: float

    def describe(self) -> str:
        v, lim = self.value / self.scale, self.limit / self.scale
        flag = " (active)" if self.active else ""
        return f"{self.name}: {v:.6g} {self.unit}, limit {lim:.6g} {self.unit}{flag}"


@dataclass(frozen=True)
class Conflict:
    """A constraint group that stays violated at the least-violating design.

    violation : how far beyond its limit, SI; ``unit``/``scale`` as in ConstraintState.
    """

    name: str
    violation: float
    limit: float
    unit: str
    scale: float
    meaning: str

    def describe(self) -> str:
        return (
            f"{self.name} ({self.meaning}) misses its limit {self.limit / self.scale:.6g} "
            f"{self.unit} by {self.violation / self.scale:.4g} {self.unit}"
        )


@dataclass(frozen=True)
class StartResult:
    """One start of the multi-start.

    status : IPOPT's return status, or the error that stopped the start.
    accepted : solved, all constraints within tolerance and (if required) stable.
    values : free quantities at the end of the start (SI, by name).
    objective : the study's objective there (SI metric or weighted sum; NaN if failed).
    """

    index: int
    materials: tuple[str | None, str | None]
    status: str
    success: bool
    accepted: bool
    objective: float
    values: dict[str, float]
    iterations: int
    seconds: float
    message: str = ""


@dataclass(frozen=True)
class OptimizationResult:
    """Outcome of :func:`optimize_design` (picklable: plain data and a Design).

    feasible : some start was accepted; then ``design`` is the best one.
    objective : the study's objective of the best design (the metric in SI for one
        objective, the weighted sum of base-normalised metrics for several).
    metrics : workspace and design metrics of the best design (see METRICS). [SI]
    base_metrics : the same for the base design as given (its own tube moduli), by
        forward simulation.
    constraints : every constraint group at the best design.
    active : names of the active groups and free bounds (``bound.<name>.low/high``).
    conflicts : for an infeasible study, the groups that stay violated at the
        least-violating design, most violated first.
    limiting_bounds : the free quantities at a bound in that least-violating design.
    epsilon : the Pareto bounds imposed (SI).
    """

    study: str
    feasible: bool
    objective: float
    design: Design | None
    values: dict[str, float]
    materials: tuple[str | None, str | None]
    metrics: dict[str, float]
    base_metrics: dict[str, float]
    constraints: tuple[ConstraintState, ...]
    active: tuple[str, ...]
    starts: tuple[StartResult, ...]
    conflicts: tuple[Conflict, ...] = ()
    limiting_bounds: tuple[str, ...] = ()
    epsilon: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0

    def report(self) -> str:
        """A plain-text summary for the user (file units)."""
        lines = [f"study {self.study}: " + ("feasible" if self.feasible else "INFEASIBLE")]
        if self.feasible:
            lines.append(f"objective {self.objective:.6g}; materials {self.materials}")
            lines += [f"  {k} = {v:.6g}" for k, v in self.values.items()]
            lines.append("active: " + (", ".join(self.active) or "none"))
        for c in self.conflicts:
            lines.append("  conflict: " + c.describe())
        if self.limiting_bounds:
            lines.append("  with " + ", ".join(self.limiting_bounds))
        for s in self.starts:
            lines.append(
                f"  start {s.index} {s.materials}: {s.status}"
                + ("" if s.accepted else f" (rejected{': ' + s.message if s.message else ''})")
            )
        return "\n".join(lines)


@dataclass(frozen=True)
class Evaluation:
    """A design evaluated by forward simulation on the study's sampled configurations.

    objective : as in OptimizationResult; metrics : see METRICS [SI]; constraints : every group.
    converged, stable : all sampled equilibria converged / are stable.
    violation : sum over groups of the violation in file units (0 when feasible).
    """

    objective: float
    metrics: dict[str, float]
    constraints: tuple[ConstraintState, ...]
    converged: bool
    stable: bool
    violation: float

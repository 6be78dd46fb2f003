"""vtb, the Voigt deformation testbed, from Python.

The module wraps vtb's C++ API (pybind11); it never reimplements a solver. A scene is a
vtb.Scene, a path to a TOML scene file, or a dict of the file's tables:

    import vtb
    sim = vtb.Simulation("experiments/scenes/plate517_step.toml")
    sim.apply_force([0.2, 0.025], [0.5, 0.0])   # N on the node nearest the point
    sim.step(100)                               # GIL released while it steps
    print(sim.time, sim.displacements.max())    # (nodes, dim) view of the state, no copy
    r = vtb.run("experiments/scenes/plate517_step.toml", solver="cvode")
    print(r.summary["step_seconds"], r.probe("tip")[1][-1])

Bad input raises vtb.InputError, whose text is the CLI's error line after "vtb: error: ".
docs/python.md lists every function with an example.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ._vtb import InputError, IoError, Scene, Simulation, interactive_solvers, solvers
from . import _vtb

__all__ = [
    "InputError", "IoError", "Scene", "Simulation", "RunResult", "run", "compare", "study", "sweep",
    "solvers", "interactive_solvers",
]


def _path(out: str | os.PathLike | None) -> str:
    return "" if out is None else os.fspath(out)


@dataclass
class RunResult:
    """What `vtb run` writes, as arrays: the rows of probes.csv and reactions.csv, summary.json."""

    summary: dict[str, Any]
    probes: dict[str, Any] = field(repr=False)     # t (rows,), probe [names], u (rows, 3) m
    reactions: dict[str, Any] = field(repr=False)  # t (rows,), region [names], f (rows, 3) N

    def probe(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(t, u): one probe's sample times (samples,) and displacements (samples, 3)."""
        rows = np.array([p == name for p in self.probes["probe"]], dtype=bool)
        if not rows.any():
            raise KeyError(f"no probe {name!r}; probes: {sorted(set(self.probes['probe']))}")
        return self.probes["t"][rows], self.probes["u"][rows]

    def reaction(self, region: str) -> tuple[np.ndarray, np.ndarray]:
        """(t, f): one fix's or drive's reaction force (samples, 3) over time."""
        rows = np.array([r == region for r in self.reactions["region"]], dtype=bool)
        if not rows.any():
            raise KeyError(f"no region {region!r}; regions: {sorted(set(self.reactions['region']))}")
        return self.reactions["t"][rows], self.reactions["f"][rows]


def run(scene, solver: str | None = None, dt: float | None = None, duration: float | None = None,
        out: str | os.PathLike | None = None, frames: bool = False) -> RunResult:
    """`vtb run SCENE [--solver] [--dt] [--duration] [--out]`: one run of any solver (the spring
    solvers, cvode, fem, bullet). With `out`, the same files as the CLI's are written there."""
    t = _vtb._run(scene, solver, dt, duration, _path(out), frames)
    return RunResult(json.loads(t["summary_json"]), t["probes"], t["reactions"])


def _arrays(table: dict[str, Any]) -> dict[str, Any]:
    return {k: (np.asarray(v) if not isinstance(v, list) else v) for k, v in table.items()}


def compare(scene, solvers: Sequence[str], reference: str = "fem", dt: float = 0.0,
            out: str | os.PathLike | None = None) -> dict[str, Any]:
    """`vtb compare`: each solver's errors against the reference (fem or cvode) and its timing.
    Returns {'rows': columns of compare.csv, 'decomposition': columns of decomposition.csv,
    'text': the CLI's table, ...}; `stable` is 1.0 or 0.0."""
    return _vtb._compare(scene, list(solvers), reference, dt, _path(out))


def study(scene, solvers: Sequence[str] | None = None, reference: str = "fem", quick: bool = False,
          out: str | os.PathLike | None = None, verbose: bool = False) -> dict[str, Any]:
    """`vtb study`: accuracy against cost over dt and rtol ladders against one converged
    reference; rows hold the columns of study.csv (pareto marks the front)."""
    return _vtb._study(scene, list(solvers or []), reference, quick, _path(out), verbose)


def sweep(scene, dt: Sequence[float], stiffness_scale: Sequence[float] = (1.0,),
          solvers: Sequence[str] | None = None, out: str | os.PathLike | None = None) -> dict[str, Any]:
    """`vtb sweep`: the stability map over dt and stiffness scale; rows hold the columns of
    stability.csv."""
    return _vtb._sweep(scene, list(dt), list(stiffness_scale), None if solvers is None else list(solvers), _path(out))

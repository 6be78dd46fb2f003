#!/usr/bin/env python3
"""What a step costs when Python calls it: `sim.step()` in a Python loop against the same
number of steps in one `sim.step(n)` call (the C++ loop), alternating rounds in one process,
medians of the rounds. The harness's own timing (a benchmark, not a test).

    python3 experiments/python/bench_overhead.py [--slab MESH.msh] [--rounds 7]

The 517-node plate runs its scene's default filter; --slab adds a 3D slab (a 10k-node one is
made by `vtb mesh generate slab --nodes 10000 -o slab10k.msh`).
"""

import argparse
import pathlib
import statistics
import time

import vtb

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def slab_scene(mesh: pathlib.Path) -> dict:
    return {
        "scene": {"name": f"slab-{mesh.stem}", "duration": 10.0, "output_interval": 0.01},
        "mesh": {"file": str(mesh.resolve())},
        "material": {"young_modulus": 5e4, "poisson_ratio": 0.25, "density": 1000.0, "retardation_time": 0.05},
        "fix": [{"name": "bottom", "box": [[-1, -1, -1e-6], [1, 1, 1e-6]]}],
        "load": [{"name": "press", "disc": {"center": [0.1, 0.025, 0.02], "radius": 0.01}, "total_force": [0, 0, -0.5]}],
        "solver": {"dt": 1e-3, "springs": "lloyd"},
    }


def measure(name: str, scene, steps: int, rounds: int) -> None:
    sim = vtb.Simulation(scene)
    sim.step(steps)  # warm up
    py, cpp = [], []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        py.append((time.perf_counter() - t0) / steps)
        t0 = time.perf_counter()
        sim.step(steps)
        cpp.append((time.perf_counter() - t0) / steps)
    calls = []  # the binding's own cost: a call that steps nothing (GIL released and taken back)
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step(0)
        calls.append((time.perf_counter() - t0) / steps)
    p, c, z = statistics.median(py), statistics.median(cpp), statistics.median(calls)
    print(f"{name}: {sim.num_nodes} nodes, {sim.solver} ({sim.filter or '-'}): step from a Python loop "
          f"{p * 1e6:.2f} us, in one C++ call {c * 1e6:.2f} us: {(p - c) * 1e6:+.2f} us per step "
          f"({(p / c - 1) * 100:+.1f} %); a call that steps nothing {z * 1e6:.2f} us ({z / c * 100:.1f} % of a step)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--slab", type=pathlib.Path, help="a 3D slab mesh (.msh) to measure too")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    measure("plate517", ROOT / "experiments" / "scenes" / "plate517_step.toml", 2000, args.rounds)
    if args.slab:
        measure(args.slab.stem, slab_scene(args.slab), 50, args.rounds)


if __name__ == "__main__":
    main()

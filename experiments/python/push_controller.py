#!/usr/bin/env python3
"""A closed loop from Python: a spring-damper controller pushes a node of the plate to a target
point, reading the node's position and writing its force between steps, as a user's own device
loop or controller would.

    python3 experiments/python/push_controller.py [SCENE] [--seconds 1.0]

The controller's stiffness and damping are passed with the force, so the implicit solvers
treat the coupling implicitly (stable at any gain); it prints how close the node came.
"""

import argparse
import pathlib

import numpy as np

import vtb

HERE = pathlib.Path(__file__).resolve().parent
DEFAULT_SCENE = HERE.parent / "scenes" / "plate517_step.toml"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=DEFAULT_SCENE, type=pathlib.Path)
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--push", type=float, default=0.004, help="m, how far to push the node down")
    args = ap.parse_args()

    sim = vtb.Simulation(args.scene, dt=1e-3)
    rest = sim.rest_positions
    node = int(np.argmax(rest[:, 0] + rest[:, 1]))  # the far top corner
    target = rest[node] + np.array([0.0, -args.push] + [0.0] * (sim.dim - 2))
    k = 200.0  # N/m: the controller's gain
    c = 2.0    # N s/m
    u, v = sim.displacements, sim.velocities  # views of the state: read fresh every step, no copy
    steps = int(round(args.seconds / sim.dt))
    for _ in range(steps):
        force = k * (target - (rest[node] + u[node])) - c * v[node]
        sim.apply_force(node, force, stiffness=k, damping=c)
        sim.step()
        if not sim.stable:
            print(f"unstable: {sim.failure}")
            return 1
    x = rest[node] + u[node]
    miss = np.linalg.norm(target - x)
    # Without the controller: where the scene's own loads leave the node.
    free = vtb.Simulation(args.scene, dt=1e-3)
    free.step(steps)
    miss_free = np.linalg.norm(target - (rest[node] + free.displacements[node]))
    print(f"{sim!r}: node {node} pushed {args.push * 1e3:.1f} mm down; {miss * 1e3:.3f} mm from the target after "
          f"{args.seconds:g} s ({miss_free * 1e3:.3f} mm without the controller), controller force "
          f"{np.linalg.norm(k * (target - x)):.3f} N, median step {sim.stats['step_median_us']:.1f} us")
    # The controller is a spring of stiffness k against the body's: it stops short of the target
    # by the body's reaction over k, but must come closer than the scene's loads alone leave it.
    return 0 if miss < miss_free else 1


if __name__ == "__main__":
    raise SystemExit(main())

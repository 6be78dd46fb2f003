#!/usr/bin/env python3
"""A dt sweep on a user's scene: error against CVODE and step cost of the filtered solver and
implicit Euler over a ladder of steps, drawn with matplotlib.

    python3 experiments/python/dt_sweep.py [SCENE] [--out dt_sweep.png] [--quick]

The scene's tables are read with tomllib and run as a dict (its duration shortened with
--quick): what a study script does to vary any key.
"""

import argparse
import pathlib
import tomllib

import matplotlib

matplotlib.use("Agg")  # files, no display
import matplotlib.pyplot as plt
import numpy as np

import vtb

HERE = pathlib.Path(__file__).resolve().parent
DEFAULT_SCENE = HERE.parent / "scenes" / "plate517_step.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=DEFAULT_SCENE, type=pathlib.Path)
    ap.add_argument("--out", default="dt_sweep.png", type=pathlib.Path)
    ap.add_argument("--quick", action="store_true", help="0.5 s of simulated time, three steps")
    ap.add_argument("--solvers", default="filtered,implicit-euler")
    args = ap.parse_args()

    tables = tomllib.loads(args.scene.read_text())
    if args.quick:
        tables["scene"]["duration"] = 0.5
        tables["scene"]["output_interval"] = min(tables["scene"].get("output_interval", 0.01), 0.05)
    scene = vtb.Scene.from_dict(tables, base_dir=args.scene.parent)
    base = scene.dt
    factors = [4, 1, 0.25] if args.quick else [8, 4, 2, 1, 0.5, 0.25]
    solvers = args.solvers.split(",")

    err = {s: [] for s in solvers}
    cost = {s: [] for s in solvers}
    dts = []
    for f in factors:
        dt = base * f
        if dt > scene.duration / 10:
            continue
        res = vtb.compare(scene, solvers, reference="cvode", dt=dt)
        dts.append(dt)
        for s in solvers:
            k = res["rows"]["solver"].index(s)
            stable = bool(res["rows"]["stable"][k])
            err[s].append(res["rows"]["displacement_error_max"][k] if stable else np.nan)
            cost[s].append(res["rows"]["step_median_seconds"][k] * 1e6)
        print(f"dt = {dt:g} s: " + ", ".join(f"{s} {err[s][-1]:.3g} ({cost[s][-1]:.1f} us/step)" for s in solvers))

    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6))
    for s in solvers:
        a.loglog(dts, err[s], "o-", label=s)
        b.loglog(dts, cost[s], "o-", label=s)
    a.set(xlabel="dt (s)", ylabel="max relative L2 error vs CVODE", title=scene.name)
    b.set(xlabel="dt (s)", ylabel="median step (us)", title="cost per step")
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"plot in {args.out}")


if __name__ == "__main__":
    main()

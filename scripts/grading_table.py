#!/usr/bin/env python3
"""Graded against uniform on a scene's own body (docs/meshes.md, "Grading toward where the scene
acts"): is the mesh that is fine only where the scene acts as good as one fine everywhere?

SCENE is a haptics scene whose [mesh] generates a surface with a refine table (as
experiments/scenes/bean_press.toml). Meshes: the scene's graded one, and a uniform one at the
refine size. Runs on both: (1) a disc load of the tool tip's radius at the first refine centre
(--force, N), the displacement at rest along the load, read twice: under the disc (a load probe:
the load-weighted mean of its nodes, what the load works through) and at the node nearest its
centre; linear P1 FEM (static) and the springs (--springs, default the fit; filtered, run to rest); (2) the scene's own haptic
session in lockstep with the lag-free tensor-multigrid filter, the mean force while the hand
holds (--hold, s). Prints one markdown table with each spring step's median. Fits are cached
as any run's.

Usage: scripts/grading_table.py SCENE [--build DIR] [--force FX,FY,FZ] [--hold T0,T1]
                                [--springs S] [--keep DIR]   (the bean: about a minute, fits cached)
"""
import argparse
import csv
import json
import math
import pathlib
import subprocess
import sys
import tempfile
import tomllib


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {v!r}")


def table(name, d, array=False):
    head = f"[[{name}]]" if array else f"[{name}]"
    return head + "\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in d.items())


def run(cmd):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"grading_table: {' '.join(map(str, cmd))} failed:\n{r.stderr.strip()}")
    return r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", type=pathlib.Path)
    ap.add_argument("--build", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent / "build")
    ap.add_argument("--force", default="0,0,-0.05", help="the disc load's total force, N (default 0,0,-0.05)")
    ap.add_argument("--hold", default="1.5,1.95", help="the haptic session's hold window, s (default 1.5,1.95)")
    ap.add_argument("--springs", default="auto", help="the springs' calibration (default auto: the fit)")
    ap.add_argument("--keep", type=pathlib.Path, help="keep the meshes, scenes and outputs here")
    a = ap.parse_args()
    vtb = a.build / "bin" / "vtb"
    scene_path = a.scene.resolve()
    sc = tomllib.loads(scene_path.read_text())
    gen = sc["mesh"]["generate"]
    refine = gen["refine"][0] if isinstance(gen["refine"], list) else gen["refine"]
    surface = (scene_path.parent / gen["file"]).resolve()
    centre, h = refine["center"], refine["size"]
    tip = sc["haptics"].get("tip_radius", 0.004)
    force = [float(x) for x in a.force.split(",")]
    t0, t1 = (float(x) for x in a.hold.split(","))

    work = a.keep or pathlib.Path(tempfile.mkdtemp(prefix="grading-"))
    work.mkdir(parents=True, exist_ok=True)
    meshes = {"uniform": work / "uniform.msh", "graded": work / "graded.msh"}
    run([vtb, "mesh", "generate", "surface", surface, "--size", h, "-o", meshes["uniform"]])
    refine_args = []
    for r in gen["refine"] if isinstance(gen["refine"], list) else [gen["refine"]]:
        refine_args += ["--refine-near", ",".join(map(str, r["center"])), "--refine-radius", r["radius"],
                        "--refine-size", r["size"]]
        if "growth" in r:
            refine_args += ["--refine-growth", r["growth"]]
    run([vtb, "mesh", "generate", "surface", surface, "--size", gen["cell_size"], *refine_args, "-o", meshes["graded"]])

    rows = {}
    for name, msh in meshes.items():
        nodes = int(run([vtb, "mesh", "info", msh]).split("nodes:")[1].split()[0])
        disc = table("scene", {"name": f"disc-{name}", "duration": 2.0, "output_interval": 0.05})
        disc += table("mesh", {"file": str(msh)}) + table("material", sc["material"])
        for f in sc.get("fix", []):
            disc += table("fix", f, array=True)
        disc += table("load", {"name": "tool", "disc": {"center": centre, "radius": tip}, "total_force": force,
                               "ramp": 0.3}, True)
        disc += table("probe", {"name": "centre", "point": centre}, True)
        disc += table("probe", {"name": "under", "load": "tool"}, True)
        answers = {}
        for model, solver in (("fem", {"kind": "fem", "static": True, "dt": 0.05}),
                              ("springs", {"kind": "filtered", "dt": 0.005, "springs": a.springs})):
            path = work / f"disc_{name}_{model}.toml"
            path.write_text(disc + table("solver", solver))
            out = work / f"disc_{name}_{model}"
            run([vtb, "run", path, "--out", out])
            rows_out = list(csv.DictReader(open(out / "probes.csv")))
            for probe in ("centre", "under"):
                last = [r for r in rows_out if r["probe"] == probe][-1]
                along = sum(float(last[k]) * f for k, f in zip(("ux", "uy", "uz"), force)) / math.hypot(*force)
                answers[f"{model}_{probe}"] = along
            if model == "springs":
                answers["step_us"] = 1e6 * json.load(open(out / "summary.json"))["step_seconds"]["median"]
        text = scene_path.read_text()
        gen_line = next(line for line in text.splitlines() if line.startswith("generate"))
        text = text.replace(gen_line, f"file = {json.dumps(str(msh))}")
        text = text.replace('kind = "filtered"', f'kind = "filtered"\nfilter = "tensor-multigrid"\nsprings = "{a.springs}"', 1)
        hap = work / f"haptics_{name}.toml"
        hap.write_text(text)
        out = work / f"haptics_{name}"
        run([vtb, "haptics", hap, "--lockstep", "--out", out])
        trace = [r for r in csv.DictReader(open(out / "haptics.csv")) if t0 <= float(r["t"]) <= t1]
        answers["held"] = sum(math.hypot(float(r["fx"]), float(r["fy"])) for r in trace) / len(trace)
        answers["haptic_step_us"] = json.load(open(out / "summary.json"))["physics_step_median_us"]
        answers["nodes"] = nodes
        rows[name] = answers

    u, g = rows["uniform"], rows["graded"]
    pct = lambda key: 100 * (g[key] / u[key] - 1)
    print(f"graded ({g['nodes']:,} nodes) against uniform ({u['nodes']:,} nodes, h = {h * 1e3:g} mm): "
          f"{g['nodes'] / u['nodes']:.2f} of the nodes")
    print("| answer | uniform | graded | graded vs uniform | step, uniform / graded |")
    print("|---|---|---|---|---|")
    where = {"under": "under the disc (the load probe)", "centre": "at the disc's centre node"}
    for probe in ("under", "centre"):
        key = f"fem_{probe}"
        print(f"| disc load, P1 FEM static, {where[probe]} | {u[key] * 1e3:.4f} mm | {g[key] * 1e3:.4f} mm "
              f"| {pct(key):+.1f} % | |")
    for probe in ("under", "centre"):
        key = f"springs_{probe}"
        print(f"| disc load, springs ({a.springs}) at rest, {where[probe]} | {u[key] * 1e3:.4f} mm "
              f"| {g[key] * 1e3:.4f} mm | {pct(key):+.1f} % | {u['step_us'] / 1e3:.2f} / {g['step_us'] / 1e3:.2f} ms "
              f"({u['step_us'] / g['step_us']:.1f}x) |")
    print(f"| tool tip's held force, lockstep | {u['held']:.4f} N | {g['held']:.4f} N | {pct('held'):+.1f} % "
          f"| {u['haptic_step_us'] / 1e3:.2f} / {g['haptic_step_us'] / 1e3:.2f} ms "
          f"({u['haptic_step_us'] / g['haptic_step_us']:.1f}x) |")


if __name__ == "__main__":
    main()

"""The module's numbers are the CLI's: one code path (harness::run, run_compare, run_sweep), so
the files and the arrays agree to the last printed digit."""

import csv
import json

import numpy as np
import pytest

import vtb
from conftest import run_cli

# summary.json keys that time the run (wall clock): everything else must be equal.
TIMING = {"precompute_seconds", "step_seconds", "total_seconds", "calibration_seconds", "realtime_factor"}


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_run_writes_the_cli_files(tmp_path, plate_scene, cli):
    r = vtb.run(plate_scene, out=tmp_path / "py")
    p = run_cli(cli, "run", plate_scene, "--out", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    for name in ("probes.csv", "reactions.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    a = json.loads((tmp_path / "py" / "summary.json").read_text())
    b = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert {k: v for k, v in a.items() if k not in TIMING} == {k: v for k, v in b.items() if k not in TIMING}
    assert r.summary == a


def test_run_arrays_are_the_files_numbers(tmp_path, plate_scene, cli):
    """probes.csv prints 10 significant digits: the arrays printed so are the file's text."""
    r = vtb.run(plate_scene)
    run_cli(cli, "run", plate_scene, "--out", tmp_path)
    table = rows(tmp_path / "probes.csv")
    assert len(table) == len(r.probes["t"])
    for k, row in enumerate(table):
        assert row["probe"] == r.probes["probe"][k]
        assert row["t"] == f"{r.probes['t'][k]:.10g}"
        for d, c in enumerate(("ux", "uy", "uz")):
            assert float(row[c]) == float(f"{r.probes['u'][k, d]:.10g}")
    t, u = r.probe("tip")
    assert u.shape == (len(t), 3) and u[-1, 0] > 0  # pulled to the right, in metres
    assert (u[:, 2] == 0).all()  # 2D: uz = 0


@pytest.mark.parametrize("solver", ["cvode", "implicit-euler", "filtered-tensor"])
def test_other_solvers_run_like_the_cli(tmp_path, plate_scene, cli, solver):
    r = vtb.run(plate_scene, solver=solver, out=tmp_path / "py")
    run_cli(cli, "run", plate_scene, "--solver", solver, "--out", tmp_path / "cli")
    assert (tmp_path / "py" / "probes.csv").read_bytes() == (tmp_path / "cli" / "probes.csv").read_bytes()
    assert r.summary["solver"] == json.loads((tmp_path / "cli" / "summary.json").read_text())["solver"]


def test_compare_columns_are_compare_csv(tmp_path, plate_scene, cli):
    """compare.csv prints 6 significant digits (%g)."""
    res = vtb.compare(plate_scene, ["filtered", "implicit-euler"], reference="cvode")
    p = run_cli(cli, "compare", plate_scene, "--solvers", "filtered,implicit-euler", "--reference", "cvode",
                "--out", tmp_path)
    assert p.returncode == 0, p.stderr
    table = rows(tmp_path / "compare.csv")
    assert [r["solver"] for r in table] == res["rows"]["solver"]
    for k, row in enumerate(table):
        for col in ("displacement_error_max", "displacement_error_final", "probe_error_max", "reaction_error_max",
                    "dt", "steps"):
            assert row[col] == f"{res['rows'][col][k]:.6g}", col
    assert res["rows"]["displacement_error_max"].dtype == np.float64
    dec = rows(tmp_path / "decomposition.csv")
    assert [d["run"] for d in dec] == res["decomposition"]["run"]


def test_sweep_columns_are_stability_csv(tmp_path, plate_scene, cli):
    res = vtb.sweep(plate_scene, dt=[1e-3, 1e-2], solvers=["filtered-full", "explicit"])
    p = run_cli(cli, "sweep", plate_scene, "--dt", "1e-3,1e-2", "--solvers", "filtered-full,explicit",
                "--out", tmp_path)
    assert p.returncode == 0, p.stderr
    table = rows(tmp_path / "stability.csv")
    assert [r["solver"] for r in table] == res["rows"]["solver"]
    for k, row in enumerate(table):
        assert (row["stable"] == "true") == bool(res["rows"]["stable"][k])
        for col in ("dt", "max_strain", "displacement_error_max"):
            assert row[col] == f"{res['rows'][col][k]:.6g}", col
    # the explicit scheme at 1000x its limit is the map's unstable cell
    assert not res["rows"]["stable"][res["rows"]["solver"].index("explicit")]


def test_study_columns_are_study_csv(tmp_path, plate_scene, cli):
    """A quick study against CVODE (deterministic errors; timing columns are not compared);
    study.csv prints 8 significant digits."""
    solvers = ["filtered-full", "implicit-euler", "cvode"]
    res = vtb.study(plate_scene, solvers=solvers, reference="cvode", quick=True)
    p = run_cli(cli, "study", plate_scene, "--solvers", ",".join(solvers), "--reference", "cvode", "--quick",
                "--out", tmp_path)
    assert p.returncode == 0, p.stderr
    table = rows(tmp_path / "study.csv")
    assert [r["solver"] for r in table] == res["rows"]["solver"]
    for k, row in enumerate(table):
        for col in ("error_all", "error_probes"):
            assert row[col] == f"{res['rows'][col][k]:.8g}", col
        assert row["dt"] == f"{res['rows']['dt'][k]:.8g}"
    assert res["rows"]["pareto"].any()  # the front has at least one run


def test_readme_python_example_runs(source_dir, tmp_path):
    """The README's Python example, as a user pastes it, run from the source folder."""
    import re
    import subprocess
    import sys

    text = (source_dir / "README.md").read_text()
    block = re.search(r"```python\n(.*?)```", text, re.S)
    assert block, "README has a Python example"
    code = block.group(1)
    assert len(code.strip().splitlines()) <= 6
    p = subprocess.run([sys.executable, "-c", code], cwd=source_dir, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip()


def test_an_override_is_applied_as_the_cli_applies_it(tmp_path, plate_scene, cli):
    """vtb.Simulation's keywords and vtb run's flags go through one function
    (vtb/problem/overrides.hh): the same solver, filter and step, and the same refusal."""
    sim = vtb.Simulation(plate_scene, solver="filtered-tensor", dt=2e-3)
    p = run_cli(cli, "run", plate_scene, "--solver", "filtered-tensor", "--dt", "2e-3", "--duration", "0.01",
                "--out", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert (sim.solver, sim.filter, sim.dt) == (summary["solver"], summary["filter"], summary["dt"])
    for bad in ("-1", "0", "nan"):
        p = run_cli(cli, "run", plate_scene, "--dt", bad, "--out", tmp_path / "bad")
        assert p.returncode == 1 and not (tmp_path / "bad").exists()
        with pytest.raises(vtb.InputError) as refused:
            vtb.Simulation(plate_scene, dt=float(bad))
        assert str(refused.value) in p.stderr

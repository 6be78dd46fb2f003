"""vtb.Simulation: a scene stepped from Python, its state as numpy arrays."""

import threading

import numpy as np
import pytest

import vtb


def test_arrays_have_the_mesh_shapes(plate_scene):
    sim = vtb.Simulation(plate_scene)
    n = sim.num_nodes
    assert sim.dim == 2 and n == 41 * 11  # the 40 x 10 structured plate
    for a in (sim.displacements, sim.velocities, sim.positions, sim.rest_positions, sim.external_forces,
              sim.internal_forces()):
        assert a.shape == (n, 2) and a.dtype == np.float64
    assert sim.spring_strains().shape == (sim.num_springs,)
    assert sim.springs_nodes.shape == (sim.num_springs, 2)
    assert sim.cells.shape == (40 * 10 * 2, 3) and sim.cell_strains().shape == (800,)
    # rest positions span the scene's [0, 0.2] x [0, 0.05] m
    assert np.allclose(sim.rest_positions.min(axis=0), [0, 0]) and np.allclose(sim.rest_positions.max(axis=0), [0.2, 0.05])


def test_state_arrays_are_views_of_the_state(plate_scene):
    sim = vtb.Simulation(plate_scene)
    u = sim.displacements
    assert np.shares_memory(u, sim.displacements)  # no copy
    assert not u.flags.writeable
    sim.step(10)
    assert np.abs(u).max() > 0  # the same view sees the new state
    sim.reset()
    assert np.abs(u).max() == 0 and sim.time == 0  # reset copies into the same storage
    sim.configure(dt=5e-4)
    assert np.shares_memory(u, sim.displacements)


def test_stepping_matches_the_run_bit_for_bit(plate_scene):
    """The stepper is the run's integrator: after k steps the probe equals run's sample at k dt."""
    r = vtb.run(plate_scene)
    t, u = r.probe("tip")
    sim = vtb.Simulation(plate_scene)
    node = sim.probes["tip"]
    for k in (10, 100, 200):  # samples every 10 steps of 1 ms
        sim.step(k - round(sim.time / sim.dt))
        i = int(np.argmin(np.abs(t - sim.time)))
        assert t[i] == pytest.approx(sim.time, abs=1e-12)
        assert (sim.displacements[node] == u[i, :2]).all()


def test_applied_force_moves_the_node_its_way(plate_scene):
    """A force on the free tip, against the scene's pull, held until changed: the node moves
    with it; clearing it restores the scene's response."""
    base = vtb.Simulation(plate_scene)
    base.step(100)
    sim = vtb.Simulation(plate_scene)
    node = sim.apply_force([0.2, 0.05], [0.0, -0.2])
    assert node == sim.nearest_node([0.2, 0.05])
    assert (sim.external_forces[node] == [0.0, -0.2]).all()
    sim.step(100)
    assert sim.displacements[node, 1] < base.displacements[node, 1] - 1e-4
    sim.clear_forces()
    assert not sim.external_forces.any()


def test_external_forces_view_is_writable(plate_scene):
    sim = vtb.Simulation(plate_scene)
    f = sim.external_forces
    f[sim.nearest_node([0.2, 0.0]), 1] = -0.1  # written straight into the simulation
    sim.step(50)
    assert sim.displacements[sim.nearest_node([0.2, 0.0]), 1] < 0


def test_configure_changes_the_solver_between_steps(plate_scene):
    sim = vtb.Simulation(plate_scene)
    sim.step(20)
    u = sim.displacements.copy()
    sim.configure(solver="implicit-euler", dt=2e-3, stiffness_scale=2.0)
    assert sim.solver == "implicit-euler" and sim.dt == 2e-3 and sim.filter == ""
    assert (sim.displacements == u).all()  # the state is kept
    sim.step(5)
    assert sim.time == pytest.approx(0.02 + 5 * 2e-3)
    sim.configure(solver="filtered", filter="tensor")
    assert sim.filter == "tensor"
    with pytest.raises(vtb.InputError):
        sim.configure(dt=-1.0)
    assert sim.dt == 2e-3  # the previous configuration is kept
    with pytest.raises(vtb.InputError, match="cvode"):
        sim.configure(solver="cvode")  # a whole-run solver: vtb.run/compare, not a stepper


def test_divergence_is_caught_not_raised(plate_scene):
    sim = vtb.Simulation(plate_scene, solver="explicit", dt=1e-3)  # 280x its limit
    done = sim.step(1000)
    assert done < 1000 and not sim.stable and "unstable" in sim.failure


def test_stats_report_the_steps(plate_scene):
    sim = vtb.Simulation(plate_scene)
    sim.step(30)
    st = sim.stats
    assert st["steps"] == 30 and st["step_median_us"] > 0 and st["max_strain"] > 0 and st["energy"] > 0


def test_stats_count_the_steps_over_the_step_budget(plate_scene):
    """[solver] step_budget: no step meets 1e-12 s, every step meets 1000 s; without one, 0. With
    filter = "auto" the Simulation picks within the budget as vtb run does (filter_reason)."""
    text = plate_scene.read_text().replace('filter = "full"', 'filter = "auto"')
    text = text.replace("[solver]", "[solver]\nstep_budget = 1e-12")
    tight = vtb.Simulation(vtb.Scene.from_toml(text))
    tight.step(20)
    assert tight.stats["step_budget_us"] == pytest.approx(1e-6)
    assert tight.stats["steps_over_budget"] == 20
    assert tight.stats["filter_reason"].startswith("no filter's measured step fits")
    loose = vtb.Simulation(vtb.Scene.from_toml(text.replace("1e-12", "1000.0")))
    loose.step(20)
    assert loose.stats["steps_over_budget"] == 0 and "fits the step budget" in loose.stats["filter_reason"]
    none = vtb.Simulation(plate_scene)
    none.step(5)
    assert none.stats["step_budget_us"] == 0 and none.stats["steps_over_budget"] == 0 and none.stats["filter_reason"] == ""


def test_step_releases_the_gil(plate_scene):
    """A Python thread runs while another steps: its counter advances during one step() call."""
    sim = vtb.Simulation(plate_scene, solver="implicit-euler")
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    th = threading.Thread(target=spin)
    th.start()
    try:
        before = count[0]
        sim.step(400)  # tens of milliseconds of C++
        during = count[0] - before
    finally:
        stop.set()
        th.join()
    assert during > 0


def test_three_dimensional_scene(source_dir):
    sim = vtb.Simulation(source_dir / "experiments" / "scenes" / "slab_press.toml", springs="lloyd")
    assert sim.dim == 3
    assert sim.displacements.shape == (sim.num_nodes, 3) and sim.cells.shape[1] == 4
    sim.step(5)
    assert np.isfinite(sim.displacements).all()

"""vtb.Scene: from a file, a dict or TOML text, validated by the CLI's reader."""

import tomllib

import pytest

import vtb
from conftest import SCENES, run_cli


def test_file_scene_reads_its_tables(plate_scene):
    s = vtb.Scene(plate_scene)
    assert s.name == "plate-step"
    assert s.duration == pytest.approx(0.2)
    assert s.solver == "filtered" and s.filter == "full" and s.springs == "lloyd"
    assert s.dt == 1e-3


def test_dict_scene_is_the_file_scene(plate_scene):
    """The same tables as a dict run to the same numbers as the file, bit for bit."""
    tables = tomllib.loads(plate_scene.read_text())
    from_dict = vtb.run(vtb.Scene.from_dict(tables, base_dir=plate_scene.parent))
    from_file = vtb.run(plate_scene)
    assert (from_dict.probes["u"] == from_file.probes["u"]).all()
    assert (from_dict.reactions["f"] == from_file.reactions["f"]).all()


def test_a_dict_is_accepted_wherever_a_scene_is(plate_scene):
    tables = tomllib.loads(plate_scene.read_text())
    tables["scene"]["duration"] = 0.05
    r = vtb.run(tables)
    assert r.summary["duration"] == pytest.approx(0.05)


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda t: t["material"].update(young_modulus=-1.0), "young_modulus"),
        (lambda t: t["solver"].update(dt=0.0), "dt"),
        (lambda t: t["material"].update(youngs_modulus=5e4), "youngs_modulus"),
        (lambda t: t["solver"].update(kind="filterd"), "filterd"),
    ],
)
def test_bad_input_raises_the_cli_error_line(tmp_path, plate_scene, cli, edit, key):
    """Bad input: vtb.InputError whose text is the CLI's one error line (after 'vtb: error: '),
    naming the key, and the CLI exits non-zero on the same file."""
    tables = tomllib.loads(plate_scene.read_text())
    edit(tables)
    bad = tmp_path / "bad.toml"
    bad.write_text(vtb.Scene.dict_to_toml(tables))
    with pytest.raises(vtb.InputError) as err:
        vtb.Scene(bad)
    assert key in str(err.value)
    p = run_cli(cli, "run", bad, "--out", tmp_path / "out")
    assert p.returncode != 0
    assert p.stderr.strip().splitlines()[-1] == f"vtb: error: {err.value}"
    assert not (tmp_path / "out").exists()  # nothing half-written
    with pytest.raises(vtb.InputError, match=key):  # the same from the dict itself
        vtb.Scene.from_dict(tables)


def test_missing_file_and_non_toml_values_raise():
    with pytest.raises(vtb.InputError, match="cannot open scene file"):
        vtb.Scene("no/such/scene.toml")
    with pytest.raises(vtb.InputError, match="scene.name"):
        vtb.Scene.from_dict({"scene": {"name": object()}})
    with pytest.raises(vtb.InputError):
        vtb.run(42)


def test_every_repository_scene_loads():
    for f in sorted(SCENES.glob("*.toml")):
        assert vtb.Scene(f).name

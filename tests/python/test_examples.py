"""The examples' picture: dt_sweep.py draws a plot that is not blank and changes with the data."""

import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE

EXAMPLE = SOURCE / "experiments" / "python" / "dt_sweep.py"


def draw(scene, out):
    p = subprocess.run([sys.executable, str(EXAMPLE), str(scene), "--quick", "--out", str(out)],
                       capture_output=True, text=True, timeout=600, env=os.environ)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_dt_sweep_plot_has_content_and_follows_the_data(tmp_path, plate_scene):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.image as mpimg

    out = draw(plate_scene, tmp_path / "a.png")
    assert "filtered" in out and "implicit-euler" in out
    a = mpimg.imread(tmp_path / "a.png")
    assert a.shape[0] > 200 and a.shape[1] > 400
    assert a[..., :3].std() > 0.05  # not a blank canvas: axes, lines and text
    # A softer plate: other errors and costs, another picture.
    stiff = tmp_path / "soft.toml"
    stiff.write_text(plate_scene.read_text().replace("young_modulus = 5.0e4", "young_modulus = 1.0e4"))
    draw(stiff, tmp_path / "b.png")
    b = mpimg.imread(tmp_path / "b.png")
    assert a.shape == b.shape and np.abs(a - b).max() > 0.1

"""fit: the mesh and the figures of `opsim fit`."""

import json

import numpy as np
import pytest

import oriented_particles as op
from conftest import REPO

PATCH = REPO / "scenes/data/patch.xyz"


def test_fit_gives_a_mesh_and_opsims_figures(tmp_path, opsim):
    result = op.fit(PATCH, open=True)
    done = opsim("fit", PATCH, "--out", tmp_path / "cli.obj", "--open")
    assert done.returncode == 0, done.stderr
    assert result.figures == json.loads(done.stdout)
    result.write_obj(tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()


def test_fit_takes_arrays():
    points = np.loadtxt(PATCH)[:, :3]
    result = op.fit(points, open=True)
    assert result.vertices.shape[1] == 3 and result.faces.shape[1] == 3
    assert result.figures["vertices"] == len(result.vertices)
    assert result.figures["faces"] == len(result.faces)
    assert result.faces.max() < len(result.vertices)
    with pytest.raises(ValueError, match="spacing"):
        op.fit(points, spacing=-1.0)


def test_fit_finds_open_data_and_approximates_noise():
    # The patch is open: found so without open=..., as opsim finds it.
    found = op.fit(PATCH)
    assert found.figures["open"] is True
    assert found.figures == op.fit(PATCH, open=True).figures
    # A noisy sphere (noise 2% of its radius) is approximated unless told
    # to interpolate.
    rng = np.random.default_rng(3)
    u = rng.normal(size=(3000, 3))
    sphere = u / np.linalg.norm(u, axis=1, keepdims=True)
    noisy = sphere + rng.normal(scale=0.02, size=sphere.shape)
    smooth = op.fit(noisy)
    assert smooth.figures["approximated"] is True
    assert smooth.figures["euler_characteristic"] == 2
    radii = np.linalg.norm(smooth.vertices, axis=1)
    assert np.sqrt(np.mean((radii - 1.0) ** 2)) < 0.01
    assert op.fit(noisy, approximate=False).figures["approximated"] is False

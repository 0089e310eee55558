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

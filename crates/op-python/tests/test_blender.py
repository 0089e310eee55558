"""Blender in the loop: the add-on runs a scene inside Blender (headless)
with this package and builds its animated objects from the arrays; they
are the frames `Scene.run` writes. Skips when `blender` is not installed."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import oriented_particles as op
from conftest import REPO, with_points
from test_simulation import read_ply_vertices

BLENDER = shutil.which("blender")
SCENE = REPO / "scenes/cookbook/skinned_hit.ron"


def python_path_for_blender(folder):
    """A folder holding this package and numpy (Debian's Blender has no
    numpy of its own) for Blender's Python to find: links to the installed
    ones (one CPython ABI, abi3 for the extension)."""
    folder.mkdir()
    for module in (op, np):
        package = Path(module.__file__).resolve().parent
        (folder / package.name).symlink_to(package)
        libs = package.parent / f"{package.name}.libs"
        if libs.is_dir():
            (folder / libs.name).symlink_to(libs)
    return folder


@pytest.mark.skipif(BLENDER is None, reason="blender is not installed")
def test_a_scene_runs_inside_blender_as_animated_objects(tmp_path):
    frames = 3
    # Particles as points: one vertex per particle in the run's frames too.
    scene = with_points(SCENE)
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(json.dumps(scene.to_dict()))
    site = python_path_for_blender(tmp_path / "site")
    report = tmp_path / "report.json"
    env = dict(os.environ, PYTHONPATH=str(site))
    done = subprocess.run(
        [BLENDER, "-b", "--factory-startup", "--python",
         str(Path(__file__).with_name("blender_check.py")), "--",
         str(REPO), str(scene_file), str(frames), str(report)],
        capture_output=True, text=True, env=env, timeout=600,
    )
    assert done.returncode == 0 and report.is_file(), done.stdout[-4000:] + done.stderr[-4000:]
    built = json.loads(report.read_text())
    # The same frames written by a run, as PLY (scene coordinates, float32).
    run = tmp_path / "run"
    scene.run(out=run, formats=["ply"], frames=frames, checkpoint_every="off")
    kinds = {name: o["kind"] for name, o in built["objects"].items()}
    assert sorted(kinds.values()).count("skin") >= 2, kinds
    for name, o in built["objects"].items():
        for k, frame in enumerate(o["frames"]):
            ply = read_ply_vertices(run / "frames" / name / f"{name}_{k:05}.ply")
            vertices = np.array(frame["vertices"], dtype=np.float32).reshape(-1, 3)
            np.testing.assert_array_equal(vertices, ply, err_msg=f"{name} frame {k}")
            if o["kind"] == "skin":
                assert frame["faces"] > 0
    assert built["fps"] == pytest.approx(json.loads((run / "summary.json").read_text())["frame_rate"])

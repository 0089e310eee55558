"""A simulation stepped from Python: its arrays are the run's frames, it
can be driven (positions, velocities, forces) and its meshes read."""

import struct

import numpy as np
import pytest

import oriented_particles as op
from conftest import REPO, with_points

SPIRAL = REPO / "scenes/spiral.ron"
SKINNED = REPO / "scenes/cookbook/skinned_hit.ron"


def read_ply_vertices(path):
    """x y z of a binary little-endian PLY frame (opsim's: x y z nx ny nz float)."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    count = int(next(l.split()[2] for l in header.splitlines() if l.startswith("element vertex")))
    values = struct.unpack_from(f"<{6 * count}f", data, end)
    return np.array(values, dtype=np.float32).reshape(count, 6)[:, :3]


@pytest.mark.parametrize("path,frames", [(SPIRAL, 6), (SKINNED, 4)], ids=["spiral", "skinned_hit"])
def test_the_arrays_at_frame_times_are_the_runs_frames(tmp_path, path, frames):
    scene = with_points(path)
    summary = scene.run(out=tmp_path, formats=["ply"], frames=frames, checkpoint_every="off")
    skinned = {o["name"] for o in scene.to_dict()["objects"] if o.get("skin")}
    sim = scene.build()
    assert sim.time == 0.0
    for k in range(frames):
        sim.advance(k / sim.frame_rate)
        for name in sim.object_names:
            xyz = sim.positions(name)
            assert xyz.dtype == np.float64 and xyz.shape[1] == 3
            frame = read_ply_vertices(tmp_path / "frames" / name / f"{name}_{k:05}.ply")
            np.testing.assert_array_equal(xyz.astype(np.float32), frame, err_msg=f"{name} frame {k}")
            if name in skinned:
                vertices, _ = sim.skin_mesh(name)
                skin = f"{name}_skin"
                frame = read_ply_vertices(tmp_path / "frames" / skin / f"{skin}_{k:05}.ply")
                np.testing.assert_array_equal(vertices.astype(np.float32), frame, err_msg=f"{skin} frame {k}")
    assert sim.time == pytest.approx(summary["sim_time"])


def test_arrays_have_their_shapes():
    sim = op.Scene.load(SPIRAL).build(threads=1)
    n = len(sim.ids("spiral"))
    assert sim.positions("spiral").shape == (n, 3)
    q = sim.orientations("spiral")
    assert q.shape == (n, 4) and q.dtype == np.float64
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    normals = sim.normals("spiral")
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert sim.velocities("spiral").shape == (n, 3)
    with pytest.raises(KeyError, match="no object \"nothing\".*its objects: .*spiral"):
        sim.positions("nothing")


def test_steps_forces_and_positions_drive_it():
    sim = op.Scene.load(SPIRAL).build()
    dt = sim.dt
    sim.step()
    assert sim.time == pytest.approx(dt)
    before = sim.velocities("spiral")
    sim.add_force("spiral", [0.0, 0.0, 100.0])
    sim.step()
    gained = sim.velocities("spiral") - before
    assert np.all(gained[:, 2] > 0), "the force pushed every particle up"
    moved = sim.positions("spiral") + [0.0, 0.0, 5.0]
    sim.set_positions("spiral", moved)
    np.testing.assert_array_equal(sim.positions("spiral"), moved)
    sim.set_velocities("spiral", np.zeros_like(moved))
    with pytest.raises(ValueError, match="rows for the"):
        sim.set_positions("spiral", moved[:2])
    with pytest.raises(ValueError, match="shape \\(n, 3\\)"):
        sim.set_positions("spiral", moved[:, :2])
    with pytest.raises(ValueError, match="must be finite"):
        sim.add_forces("spiral", np.full(moved.shape, np.nan))
    with pytest.raises(ValueError, match="only goes forward"):
        sim.advance(0.0)
    stages = sim.stage_seconds()
    assert "build" in stages and all(v >= 0 for v in stages.values())
    energies = sim.energies()
    assert set(energies) == {"kinetic", "potential", "total", "oscillation", "max_speed"}


def test_skin_and_surface_meshes():
    sim = op.Scene.load(SKINNED).build()
    name = sim.object_names[0]
    vertices, faces = sim.skin_mesh(name)
    assert vertices.shape[1] == 3 and faces.shape[1] == 3 and len(faces) > 100
    assert faces.dtype == np.int64 and faces.max() < len(vertices)
    sim2 = op.Scene.load(REPO / "scenes/sphere_surface.ron").build()
    vertices, faces = sim2.surface_mesh(sim2.object_names[0])
    assert len(faces) > 0 and faces.max() < len(vertices)
    with pytest.raises(ValueError, match="has no skin"):
        sim2.skin_mesh(sim2.object_names[0])


def test_a_diverging_simulation_raises():
    sim = op.Scene.load(REPO / "tests/data/diverge.ron").build()
    with pytest.raises(op.DivergenceError) as e:
        sim.advance(1.0)
    assert e.value.summary is None

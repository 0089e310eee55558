"""Scene.run writes what `opsim run` writes; a divergence raises
DivergenceError; Ctrl-C stops a run between frames and it resumes."""

import json
import os
import signal
import threading

import pytest

import oriented_particles as op
from conftest import REPO
from runs import assert_same_run, files

SPIRAL = REPO / "scenes/spiral.ron"
SKINNED = REPO / "scenes/cookbook/skinned_hit.ron"


def test_a_run_writes_what_opsim_run_writes(tmp_path, opsim):
    for scene, frames in ((SPIRAL, None), (SKINNED, 4)):
        flags = ["--frames", str(frames)] if frames else []
        cli = tmp_path / f"cli-{scene.stem}"
        done = opsim("run", scene, "--out", cli, "--format", "obj,ply,vtu", "--threads", "2", *flags)
        assert done.returncode == 0, done.stderr
        py = tmp_path / f"py-{scene.stem}"
        summary = op.Scene.load(scene).run(
            out=py, formats=["obj", "ply", "vtu"], threads=2, frames=frames
        )
        assert_same_run(cli, py)
        assert summary == json.loads((py / "summary.json").read_text())
        assert "checkpoint.bin" in files(py)


def test_the_frames_do_not_depend_on_the_thread_count(tmp_path):
    scene = op.Scene.load(SKINNED)
    for k in (1, 2, 3):
        summary = scene.run(out=tmp_path / f"t{k}", formats=["ply"], threads=k, frames=4,
                            checkpoint_every="off")
        assert summary["threads"] == k
    for k in (2, 3):
        names = files(tmp_path / "t1")
        assert names == files(tmp_path / f"t{k}")
        for name in names:
            if name.endswith(".ply"):
                assert (tmp_path / "t1" / name).read_bytes() == (tmp_path / f"t{k}" / name).read_bytes()


def test_a_divergence_raises_divergence_error_with_the_summary(tmp_path):
    scene = op.Scene.load(REPO / "tests/data/diverge.ron")
    with pytest.raises(op.DivergenceError) as e:
        scene.run(out=tmp_path, allow_unstable_step=True)
    message = str(e.value)
    assert "step" in message and "particle" in message, message
    assert "summary.json says diverged: true" in message
    assert e.value.summary["diverged"] is True
    assert e.value.summary == json.loads((tmp_path / "summary.json").read_text())
    assert isinstance(e.value, RuntimeError)


def test_a_divergence_matches_opsims_exit_3(tmp_path, opsim):
    scene = REPO / "tests/data/diverge.ron"
    done = opsim("run", scene, "--out", tmp_path / "cli", "--allow-unstable-step")
    assert done.returncode == 3
    with pytest.raises(op.DivergenceError) as e:
        op.Scene.load(scene).run(out=tmp_path / "py", allow_unstable_step=True)
    assert done.stderr.strip().endswith(str(e.value).replace(str(tmp_path / "py"), str(tmp_path / "cli")))


def test_a_step_beyond_the_edge_is_refused_unless_allowed(tmp_path):
    # Explicit Euler without damping: no step is stable, and the refusal says why.
    scene = op.Scene.load(REPO / "tests/data/diverge.ron")
    with pytest.raises(ValueError, match="is not stable: explicit Euler.*allow_unstable_step=True"):
        scene.run(out=tmp_path)
    assert not (tmp_path / "summary.json").exists()


def test_bad_run_arguments_are_value_errors(tmp_path):
    scene = op.Scene.load(SPIRAL)
    with pytest.raises(ValueError, match="unknown frame format \"stl\""):
        scene.run(out=tmp_path, formats=["stl"])
    with pytest.raises(ValueError, match="threads = 0"):
        scene.run(out=tmp_path, threads=0)
    with pytest.raises(ValueError, match="checkpoint_every"):
        scene.run(out=tmp_path, checkpoint_every="sometimes")


def test_progress_is_reported_and_stopping_resumes(tmp_path):
    """A progress callable sees every frame; one that raises stops the run
    after that frame (what Ctrl-C does), with a summary and a checkpoint,
    and the run resumes to the frames of an uninterrupted one."""
    scene = op.Scene.load(SPIRAL)
    seen = []
    whole = scene.run(out=tmp_path / "whole", formats=["ply"], frames=12,
                      progress=lambda k, n: seen.append((k, n)))
    assert seen[-1] == (12, 12) and len(seen) >= 2

    def stop(k, n):
        if k >= 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        scene.run(out=tmp_path / "cut", formats=["ply"], frames=12, progress=stop)
    summary = json.loads((tmp_path / "cut" / "summary.json").read_text())
    assert summary["failure"].startswith("interrupted after")
    assert summary["frames"] < 12
    resumed = scene.run(out=tmp_path / "cut", formats=["ply"], frames=12, resume=True)
    assert resumed["frames"] == whole["frames"] == 12
    for name in files(tmp_path / "whole"):
        if name.endswith(".ply"):
            assert (tmp_path / "whole" / name).read_bytes() == (tmp_path / "cut" / name).read_bytes()


def test_ctrl_c_stops_a_run_between_frames(tmp_path):
    scene = op.Scene.load(SKINNED)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            scene.run(out=tmp_path, formats=["ply"], frames=400)
    finally:
        timer.cancel()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["failure"].startswith("interrupted after")
    assert (tmp_path / "checkpoint.bin").is_file()

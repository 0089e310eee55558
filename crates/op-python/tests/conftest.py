"""Shared fixtures of the oriented_particles tests: the repository, the
shipped scenes and the ``opsim`` binary to compare with (when built)."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def shipped_scenes():
    """Every shipped scene file: scenes/*.ron, scenes/*/*.ron and the JSON ones."""
    scenes = REPO / "scenes"
    files = set(scenes.glob("*.ron")) | set(scenes.glob("*/*.ron"))
    files |= set(scenes.glob("**/*.json"))
    return sorted(files)


def opsim_binary():
    """The ``opsim`` binary: $OPSIM, else one built in the target folder
    (ci profile first, as .ci/run builds it), else one on PATH; None when
    there is none."""
    if os.environ.get("OPSIM"):
        return Path(os.environ["OPSIM"])
    targets = [Path(os.environ["CARGO_TARGET_DIR"])] if os.environ.get("CARGO_TARGET_DIR") else []
    targets.append(REPO / "target")
    for target in targets:
        for profile in ("ci", "release"):
            candidate = target / profile / "opsim"
            if candidate.is_file():
                return candidate
    found = shutil.which("opsim")
    return Path(found) if found else None


@pytest.fixture(scope="session")
def opsim():
    """A callable running ``opsim`` with arguments, returning the completed
    process; skips the test when no binary is built."""
    binary = opsim_binary()
    if binary is None:
        pytest.skip("no opsim binary (build it with `cargo build --profile ci`, or set OPSIM)")

    def call(*args, cwd=None):
        return subprocess.run(
            [str(binary), *map(str, args)], capture_output=True, text=True, cwd=cwd
        )

    return call


@pytest.fixture
def repo():
    return REPO


def with_points(path):
    """The scene at ``path`` with its particles written as points (one PLY
    vertex per particle, comparable with the simulation's arrays)."""
    import oriented_particles as op

    scene = op.Scene.load(path)
    d = scene.to_dict()
    d["outputs"]["particles"] = "Points"
    return op.Scene.from_dict(
        d, origin=scene.origin, base_dir=scene.base_dir, expected_warnings=scene.expected_warnings
    )

"""Every sequence a run writes loads through its series file with meshio, the
reader a ParaView-style pipeline takes (issue 34: ParaView time series of
everything): the particles, skin, triangulation and tools of a skinned scene
in OBJ, PLY and VTU, each series listing its frames at increasing times."""

import json

import pytest

from conftest import REPO

meshio = pytest.importorskip("meshio")

SKINNED_CUT = REPO / "tests/data/skinned_cut.ron"


def skinned_scene_with_surface(folder):
    """tests/data/skinned_cut.ron (a skinned sheet, three tools) with its
    triangulation written too."""
    text = SKINNED_CUT.read_text().replace(
        "outputs: (particles: Discs)", "outputs: (particles: Discs, triangulation: true)"
    )
    assert "triangulation: true" in text
    scene = folder / "skinned_cut_surface.ron"
    scene.write_text(text)
    return scene


def test_every_series_loads_with_meshio(tmp_path, opsim):
    scene = skinned_scene_with_surface(tmp_path)
    out = tmp_path / "run"
    done = opsim(
        "run", scene, "--out", out, "--frames", "3", "--format", "obj,ply,vtu", "--allow-breakup"
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    series = summary["files"]["series"]
    kinds = {s["stem"]: s["kind"] for s in summary["files"]["sequences"]}
    assert set(kinds.values()) == {"particles", "skin", "surface", "tool"}
    # OBJ and PLY for every sequence, VTU for all but the particles (the
    # state holds them), and the state.
    assert len(series) == 2 * len(kinds) + (len(kinds) - 1) + 1

    read = {}
    for rel in series:
        path = out / rel
        listing = json.loads(path.read_text())
        files = listing["files"]
        times = [f["time"] for f in files]
        assert len(files) == summary["frames"] == 3, rel
        assert times == sorted(set(times)), rel
        for k, t in enumerate(times):
            assert t == pytest.approx(k / summary["frame_rate"]), rel
        for f in files:
            mesh = meshio.read(path.parent / f["name"])
            assert len(mesh.points) > 0, f["name"]
            stem = path.name.split(".")[0]
            if kinds.get(stem) in ("skin", "surface", "tool"):
                triangles = sum(len(c.data) for c in mesh.cells if c.type == "triangle")
                assert triangles > 0, f["name"]
            if rel.endswith(".vtu.series") and stem != "state":
                normals = mesh.point_data["normal"]
                assert normals.shape == (len(mesh.points), 3), f["name"]
            read[(rel, f["name"])] = (len(mesh.points), sum(len(c.data) for c in mesh.cells))

    # The same skin frame in PLY and VTU: the same mesh.
    skin = next(stem for stem, kind in kinds.items() if kind == "skin")
    for k in range(3):
        ply = read[(f"frames/{skin}/{skin}.ply.series", f"{skin}_{k:05}.ply")]
        vtu = read[(f"vtu/{skin}.vtu.series", f"{skin}_{k:05}.vtu")]
        assert ply == vtu, (k, ply, vtu)

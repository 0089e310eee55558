"""The USD cache (`opsim run --format usd`, op-scene export/usd.rs) opened
with Pixar's own USD library (PyPI `usd-core`): the stage's metadata, one
prim per sequence with one time sample per frame and the counts of the PLY
frames of the same run, and no error from Pixar's validators (what
`usdchecker` runs: every registered `UsdValidation` validator in usd-core
24.11 and later, the `ComplianceChecker` before); then imported into Blender
(`wm.usd_import`, headless) with the same counts on several frames, when
the installed Blender has a USD importer (Debian's 3.4 is built without
one: the test skips). Needs only the ``opsim`` binary, not this package."""

import json
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from conftest import REPO

pxr = pytest.importorskip("pxr", reason="usd-core is not installed (pip install usd-core)")
from pxr import Usd, UsdGeom, UsdUtils  # noqa: E402

try:
    from pxr import UsdValidation
except ImportError:  # usd-core before 24.11
    UsdValidation = None

SCENE = REPO / "scenes/ball_vs_spiral.ron"
FRAMES = 5
BLENDER = shutil.which("blender")


def ply_counts(path):
    """(vertices, faces) of a binary PLY frame file, from its header."""
    with open(path, "rb") as f:
        header = f.read(4096).split(b"end_header\n")[0].decode()
    counts = {}
    for line in header.splitlines():
        words = line.split()
        if words[:1] == ["element"]:
            counts[words[1]] = int(words[2])
    return counts.get("vertex", 0), counts.get("face", 0)


@pytest.fixture(scope="module")
def usd_run(tmp_path_factory, opsim):
    """A short run of the skinned ball-and-spiral scene in PLY and USD."""
    out = tmp_path_factory.mktemp("usd") / "run"
    done = opsim("run", SCENE, "--out", out, "--frames", FRAMES, "--format", "ply,usd",
                 "--checkpoint-every", "off")
    assert done.returncode == 0, done.stderr
    return out, json.loads((out / "summary.json").read_text())


def test_usd_core_reads_the_stage_with_the_counts_of_the_ply_frames(usd_run):
    out, summary = usd_run
    path = out / summary["files"]["usd"]["file"]
    assert path.name == "run.usda"
    stage = Usd.Stage.Open(str(path))
    assert stage is not None
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == summary["frame_rate"]
    assert stage.GetFramesPerSecond() == summary["frame_rate"]
    assert stage.GetStartTimeCode() == 0
    assert stage.GetEndTimeCode() == FRAMES - 1
    assert stage.GetDefaultPrim().GetPath() == "/Run"
    objects = {o["name"]: o for o in summary["objects"]}
    prims = summary["files"]["usd"]["prims"]
    sequences = summary["files"]["sequences"]
    assert [p["name"] for p in prims] == [s["name"] for s in sequences]
    kinds = {p["kind"] for p in prims}
    assert {"particles", "skin"} <= kinds, kinds
    for seq, entry in zip(sequences, prims):
        prim = stage.GetPrimAtPath(entry["path"])
        assert prim.IsValid(), entry
        if entry["kind"] == "particles":
            points = UsdGeom.Points(prim)
            assert points, entry
            assert points.GetPointsAttr().GetNumTimeSamples() == FRAMES
            orientations = UsdGeom.PrimvarsAPI(prim).GetPrimvar("orientations")
            assert orientations.GetInterpolation() == UsdGeom.Tokens.vertex
            for k in (0, 2, FRAMES - 1):
                n = len(points.GetPointsAttr().Get(k))
                assert n == objects[seq["name"]]["particles"], entry
                assert len(points.GetWidthsAttr().Get(k)) == n
                assert len(points.GetNormalsAttr().Get(k)) == n
                quats = orientations.Get(k)
                assert len(quats) == n
                assert all(abs(q.GetLength() - 1) < 1e-5 for q in quats)
        else:
            mesh = UsdGeom.Mesh(prim)
            assert mesh, entry
            assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
            assert mesh.GetPointsAttr().GetNumTimeSamples() == FRAMES
            stem = seq["stem"]
            for k in (0, 2, FRAMES - 1):
                vertices, faces = ply_counts(out / "frames" / stem / f"{stem}_{k:05}.ply")
                assert len(mesh.GetPointsAttr().Get(k)) == vertices, (entry, k)
                assert len(mesh.GetNormalsAttr().Get(k)) == vertices, (entry, k)
                assert len(mesh.GetFaceVertexCountsAttr().Get(k)) == faces, (entry, k)
                assert len(mesh.GetFaceVertexIndicesAttr().Get(k)) == 3 * faces
                if entry["kind"] == "skin":
                    assert faces > 0


def validation_errors(path):
    """The errors Pixar's validators find in the stage at ``path``."""
    if UsdValidation is None:
        checker = UsdUtils.ComplianceChecker(skipARKitRootLayerCheck=True)
        checker.CheckCompliance(str(path))
        return list(checker.GetErrors()) + list(checker.GetFailedChecks())
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    assert len(validators) > 10, validators
    errors = UsdValidation.ValidationContext(validators).Validate(Usd.Stage.Open(str(path)))
    return [f"{e.GetName()}: {e.GetMessage()}" for e in errors
            if e.GetType() == UsdValidation.ValidationErrorType.Error]


def test_usdchecker_finds_no_error(usd_run, tmp_path):
    out, summary = usd_run
    path = out / summary["files"]["usd"]["file"]
    assert validation_errors(path) == []
    # The validators do run: the same stage without its metersPerUnit fails.
    broken = tmp_path / "broken.usda"
    text = path.read_text()
    assert "metersPerUnit = 1.0" in text
    broken.write_text(text.replace("metersPerUnit = 1.0", ""))
    assert any("metersPerUnit" in e for e in validation_errors(broken))


@pytest.mark.skipif(BLENDER is None, reason="blender is not installed")
def test_blender_imports_the_usd_with_the_counts_of_the_stage(usd_run, tmp_path):
    out, summary = usd_run
    report = tmp_path / "blender.json"
    frames = [0, 2, FRAMES - 1]
    done = subprocess.run(
        [BLENDER, "-b", "--factory-startup", "--python",
         str(Path(__file__).with_name("usd_blender_check.py")), "--",
         str(out / summary["files"]["usd"]["file"]), ",".join(map(str, frames)), str(report)],
        capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0 and report.is_file(), done.stdout[-4000:] + done.stderr[-4000:]
    seen = json.loads(report.read_text())
    if not seen["usd_import"]:
        pytest.skip("this Blender has no USD importer (built without USD, as Debian's 3.4 is)")
    stage = Usd.Stage.Open(str(out / summary["files"]["usd"]["file"]))
    meshes = [p for p in summary["files"]["usd"]["prims"] if p["kind"] != "particles"]
    assert meshes
    for entry in meshes:
        name = entry["path"].rsplit("/", 1)[1]
        assert name in seen["objects"], (name, sorted(seen["objects"]))
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(entry["path"]))
        for k in frames:
            got = seen["objects"][name][str(k)]
            want = (len(mesh.GetPointsAttr().Get(k)), len(mesh.GetFaceVertexCountsAttr().Get(k)))
            assert (got["vertices"], got["faces"]) == want, (name, k)
    # What Blender 3.4 makes of the particles' Points prims is recorded for
    # the docs: it imports none of them (no point cloud importer).
    particles = [p["path"].rsplit("/", 1)[1] for p in summary["files"]["usd"]["prims"]
                 if p["kind"] == "particles"]
    seen_particles = [n for n in particles if n in seen["objects"]]
    if seen_particles:
        for name in seen_particles:
            prim = UsdGeom.Points(stage.GetPrimAtPath(f"/Run/{name}"))
            for k in frames:
                assert seen["objects"][name][str(k)]["vertices"] == len(prim.GetPointsAttr().Get(k))
    assert seen["fps"] == pytest.approx(summary["frame_rate"])

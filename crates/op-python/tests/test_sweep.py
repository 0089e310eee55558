"""The Dask sweep example: a wedge of 16 variants on a LocalCluster of 2
workers, each task writing its own run folder and returning its summary's
row; the same variant gives the same frames when run here."""

import importlib.util
import json
import sys
from pathlib import Path

import pytest

import oriented_particles as op
from oriented_particles.sweep import run_variant, set_field, table, variant_name, wedge
from runs import assert_same_run

pytest.importorskip("distributed")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "dask_sweep.py"


def load_example():
    spec = importlib.util.spec_from_file_location("dask_sweep", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["dask_sweep"] = module
    spec.loader.exec_module(module)
    return module


def test_wedges_and_fields():
    assert wedge({"a": [1, 2], "b.c": [3, 4]}) == [
        {"a": 1, "b.c": 3}, {"a": 1, "b.c": 4}, {"a": 2, "b.c": 3}, {"a": 2, "b.c": 4}]
    d = {"objects": [{"mass": 1}], "world": {}}
    set_field(d, "objects.0.mass", 2)
    set_field(d, "world.dt", 0.1)
    assert d == {"objects": [{"mass": 2}], "world": {"dt": 0.1}}
    with pytest.raises(KeyError, match="materials"):
        set_field(d, "materials.m.form", 1)
    assert variant_name({"materials.m.form": 0.5, "world.linear_damping": 0.1}) == "form=0.5,linear_damping=0.1"


def test_the_sweep_runs_16_variants_on_2_workers(tmp_path, capsys):
    example = load_example()
    rows = example.main(["--out", str(tmp_path), "--workers", "2", "--frames", "41"])
    assert len(rows) == 16
    assert [r["variant"] for r in rows] == [variant_name(s) for s in wedge(example.AXES)]
    assert len({r["host"] for r in rows}) == 2, "both workers ran tasks"
    for r in rows:
        summary = json.loads((Path(r["out"]) / "summary.json").read_text())
        assert summary["frames"] == 41
        assert r["wire.rest_shape_error_max"] == summary["objects"][0]["rest_shape_error_max"]
    printed = capsys.readouterr().out
    assert printed.strip() == (tmp_path / "table.md").read_text().strip()
    assert printed.count("\n") == 18, "a header, its rule and 16 rows"
    # Deterministic: a variant run here gives the frames a worker wrote.
    scene = op.Scene.load(example.REPO / "scenes/cookbook/wire_bend_release.ron")
    settings = wedge(example.AXES)[5]
    here = run_variant(scene.to_dict(), settings, str(tmp_path / "here"), origin=scene.origin,
                       expected_warnings=scene.expected_warnings, formats=["ply"], frames=41,
                       checkpoint_every="off")
    assert_same_run(rows[5]["out"], here["out"])
    assert table([here]).startswith("| variant |")

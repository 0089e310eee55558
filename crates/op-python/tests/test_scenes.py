"""Scenes from files and dicts: every shipped scene round-trips through
to_dict / from_dict, bad input raises ValueError with opsim's message."""

import json
import pickle

import numpy as np
import pytest

import oriented_particles as op
from conftest import REPO, shipped_scenes

SCENES = shipped_scenes()


def test_the_shipped_scenes_are_found():
    names = {p.name for p in SCENES}
    assert {"spiral.ron", "chain.json", "cloth_on_box.ron", "tight_curvature.ron"} <= names
    assert len(SCENES) > 40


@pytest.mark.parametrize("path", SCENES, ids=lambda p: str(p.relative_to(REPO / "scenes")))
def test_every_shipped_scene_round_trips_through_a_dict(path):
    scene = op.Scene.load(path)
    d = scene.to_dict()
    assert d["name"] == scene.name
    again = op.Scene.from_dict(
        d,
        origin=scene.origin,
        base_dir=scene.base_dir,
        expected_warnings=scene.expected_warnings,
    )
    assert again.to_dict() == d
    assert again == scene
    # The dict is plain JSON data, as a .json scene file holds.
    assert op.Scene.from_dict(json.loads(json.dumps(d)), origin=scene.origin,
                              base_dir=scene.base_dir,
                              expected_warnings=scene.expected_warnings) == scene


def test_a_ron_header_gives_the_expected_warnings():
    scene = op.Scene.load(REPO / "scenes/extreme/tight_curvature.ron")
    assert scene.expected_warnings, "the scene declares its breakup"
    assert scene.object_names == ["chain"]
    assert scene.source.name == "tight_curvature.ron"


def test_a_scene_pickles():
    scene = op.Scene.load(REPO / "scenes/extreme/tight_curvature.ron")
    again = pickle.loads(pickle.dumps(scene))
    assert again == scene
    assert again.expected_warnings == scene.expected_warnings
    assert again.origin == scene.origin


def chain(**changes):
    d = {
        "name": "t",
        "materials": {"m": {}},
        "objects": [
            {"name": "a", "material": "m", "generator": {"Chain": {"count": 3, "spacing": 1}}}
        ],
    }
    d["objects"][0].update(changes)
    return d


def test_numpy_values_stand_for_numbers_and_lists():
    scene = op.Scene.from_dict(chain(mass=np.float32(2.0), velocity=np.array([1.0, 0.0, 0.0])))
    obj = scene.to_dict()["objects"][0]
    assert obj["mass"] == 2.0 and obj["velocity"] == [1.0, 0.0, 0.0]


def test_a_value_out_of_range_is_a_value_error_with_its_field_path():
    with pytest.raises(ValueError) as e:
        op.Scene.from_dict(chain(mass=-1))
    assert str(e.value) == '<dict>: objects[0] "a".mass = -1: must be finite and > 0'


def test_an_unknown_field_names_its_path():
    d = chain()
    d["objects"][0]["generator"]["Chain"]["colour"] = 2
    with pytest.raises(ValueError) as e:
        op.Scene.from_dict(d)
    message = str(e.value)
    assert message.startswith("<dict>: objects[0].generator.Chain"), message
    assert "unknown field `colour`" in message


def test_a_wrong_type_and_a_missing_field_name_their_paths():
    with pytest.raises(ValueError, match=r"objects\[0\].mass: invalid type: string"):
        op.Scene.from_dict(chain(mass="heavy"))
    d = chain()
    del d["objects"][0]["material"]
    with pytest.raises(ValueError, match="missing field `material`"):
        op.Scene.from_dict(d)


def test_not_json_data_is_a_value_error():
    with pytest.raises(ValueError, match="not JSON data"):
        op.Scene.from_dict(chain(mass=float("inf")))
    with pytest.raises(TypeError):
        op.Scene.from_dict([1, 2])


def test_the_messages_are_opsims(tmp_path, opsim):
    """The same bad scene as a file: `opsim check` prints the message the
    package raises (after its origin)."""
    for bad in (chain(mass=-1), chain(generator={"Chain": {"count": 0, "spacing": 1}})):
        path = tmp_path / "bad.json"
        path.write_text(json.dumps(bad))
        with pytest.raises(ValueError) as e:
            op.Scene.load(path)
        with pytest.raises(ValueError) as from_dict:
            op.Scene.from_dict(bad, origin=str(path))
        checked = opsim("check", path)
        assert checked.returncode == 2
        assert checked.stderr.strip() == f"opsim: error: {e.value}"
        assert str(from_dict.value) == str(e.value)


def test_a_missing_file_is_an_os_error():
    with pytest.raises(FileNotFoundError, match="cannot read /nonexistent/scene.ron"):
        op.Scene.load("/nonexistent/scene.ron")
    with pytest.raises(ValueError, match="unsupported scene file extension"):
        op.Scene.load(REPO / "README.md")


def test_work_limits_are_opsims():
    d = chain()
    d["world"] = {"duration": 1e9, "dt": 1e-3}
    with pytest.raises(ValueError, match="no-work-limits|work limit|steps"):
        op.Scene.from_dict(d)
    op.Scene.from_dict(d, no_work_limits=True)
    with pytest.raises(ValueError, match="max_particle_steps"):
        op.Scene.from_dict(chain(), max_particle_steps=-1)


def test_the_stable_step_is_estimated():
    estimate = op.Scene.load(REPO / "scenes/spiral.ron").stable_step()
    assert estimate["dt_max"] > 0
    assert estimate["recommended"] == pytest.approx(0.7 * estimate["dt_max"])
    assert estimate["object"] == "spiral"

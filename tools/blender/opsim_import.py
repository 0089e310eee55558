# SPDX-License-Identifier: MIT OR Apache-2.0
"""Blender add-on: import an `opsim run` output folder as an animated sequence.

Install: Edit > Preferences > Add-ons > Install..., choose this file, tick
"Import-Export: opsim run". Use: File > Import > opsim run (summary.json),
pick the run's `summary.json`. Every sequence the run wrote (each scene
object's particles, skins, triangulations and tools) becomes one Blender
object whose mesh is swapped on every frame change; the scene's frame rate
and range are set from the summary. Opsim frame k is Blender frame k.

Frames are read in the run's first mesh format: OBJ (y-up files, imported
with Blender's OBJ importer's own axis defaults, forward -Z and up Y) or PLY
(scene coordinates, z-up). Either way Blender shows scene coordinates: the
scene's +z (against gravity in the shipped scenes) is Blender's +Z.

File > Import > opsim scene (run in Blender) runs a scene file inside
Blender instead, with the `oriented_particles` Python package (README
"Python"), and builds the same animated objects from its arrays, with no
file in between (`run_scene`).

Headless use (the repository's tests do this):

    blender -b --factory-startup --python-expr \
      "import sys; sys.path.insert(0, 'tools/blender'); import opsim_import as o; \
       o.register(); o.import_run('RUN/summary.json')"
"""

import json
import math
import os

import bpy
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

bl_info = {
    "name": "opsim run",
    "author": "oriented-particles",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > opsim run (summary.json)",
    "description": "Import an opsim run folder, or run a scene in Blender, as animated objects",
    "category": "Import-Export",
}

# Custom property on each sequence object: the names of its per-frame meshes.
FRAMES_KEY = "opsim_frames"


def has_operator(module, name):
    """Whether `bpy.ops.<module>.<name>` exists in this Blender (attribute
    access alone always succeeds)."""
    try:
        getattr(getattr(bpy.ops, module), name).get_rna_type()
        return True
    except (AttributeError, KeyError):
        return False


def _import_obj(path):
    """Imports one OBJ file with Blender's default OBJ axes; returns the new objects."""
    before = set(bpy.data.objects)
    if has_operator("wm", "obj_import"):
        bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
    else:
        bpy.ops.import_scene.obj(filepath=path, axis_forward="-Z", axis_up="Y")
    return [o for o in bpy.data.objects if o not in before]


def _import_ply(path):
    """Imports one PLY file (scene coordinates, z-up); returns the new objects."""
    before = set(bpy.data.objects)
    if has_operator("wm", "ply_import"):
        bpy.ops.wm.ply_import(filepath=path, forward_axis="Y", up_axis="Z")
    else:
        bpy.ops.import_mesh.ply(filepath=path)
    return [o for o in bpy.data.objects if o not in before]


def _load_mesh(path, fmt, name):
    """The mesh of one frame file, with the importer's axis conversion baked
    into its vertices (so the sequence object needs no transform)."""
    new = _import_obj(path) if fmt == "obj" else _import_ply(path)
    meshes = [o for o in new if o.type == "MESH"]
    if meshes:
        ob = meshes[0]
        mesh = ob.data
        mesh.transform(ob.matrix_world)
    else:
        # An empty file (an object whose particles were all erased): an
        # importer makes no object from it.
        mesh = bpy.data.meshes.new(name)
    for o in new:
        bpy.data.objects.remove(o, do_unlink=True)
    mesh.name = name
    return mesh


def _frame_path(run, stem, k, fmt):
    return os.path.join(run, "frames", stem, "%s_%05d.%s" % (stem, k, fmt))


def _set_frame_rate(scene, rate):
    """Blender's rate is fps / fps_base with an integer fps."""
    fps = max(1, int(math.ceil(rate - 1e-9)))
    scene.render.fps = fps
    scene.render.fps_base = fps / rate


@bpy.app.handlers.persistent
def _swap_meshes(scene, *_args):
    """Frame-change handler: gives each sequence object its frame's mesh."""
    for ob in scene.objects:
        names = ob.get(FRAMES_KEY)
        if not names:
            continue
        k = min(max(scene.frame_current, 0), len(names) - 1)
        mesh = bpy.data.meshes.get(names[k])
        if mesh is not None and ob.data != mesh:
            ob.data = mesh


def import_run(path, fmt=None, collection_name=None):
    """Imports the run whose `summary.json` (or folder) is `path`.

    Returns the created objects, one per sequence, in the summary's order.
    `fmt` is "obj" or "ply" (default: OBJ if the run wrote it, else PLY).
    """
    run = path if os.path.isdir(path) else os.path.dirname(path)
    with open(os.path.join(run, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    files = summary.get("files", {})
    formats = [x for x in files.get("formats", []) if x in ("obj", "ply")]
    if fmt is None:
        if not formats:
            raise ValueError("%s: the run wrote no OBJ or PLY frames" % run)
        fmt = formats[0]
    if fmt not in formats:
        raise ValueError("%s: the run wrote no %s frames (it wrote %s)" % (run, fmt, formats))
    frames = int(summary["frames"])
    scene = bpy.context.scene
    collection = bpy.data.collections.new(collection_name or summary["scene"])
    scene.collection.children.link(collection)
    created = []
    for seq in files.get("sequences", []):
        names = []
        for k in range(frames):
            mesh = _load_mesh(
                _frame_path(run, seq["stem"], k, fmt), fmt, "%s.%05d" % (seq["name"], k)
            )
            # Meshes shown by no object would be dropped on saving.
            mesh.use_fake_user = True
            names.append(mesh.name)
        ob = bpy.data.objects.new(seq["name"], bpy.data.meshes[names[0]])
        ob[FRAMES_KEY] = names
        ob["opsim_kind"] = seq["kind"]
        collection.objects.link(ob)
        created.append(ob)
    _set_frame_rate(scene, float(summary["frame_rate"]))
    scene.frame_start = 0
    scene.frame_end = max(frames - 1, 0)
    scene["opsim_up"] = summary.get("up", [0.0, 0.0, 1.0])
    if _swap_meshes not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_swap_meshes)
    scene.frame_set(0)
    return created


def _mesh_from_arrays(name, vertices, faces=None):
    """A mesh from numpy arrays: vertices (n, 3) and triangles (k, 3), set
    in bulk (foreach_set), no file in between."""
    import numpy as np

    mesh = bpy.data.meshes.new(name)
    vertices = np.ascontiguousarray(vertices, dtype=np.float32)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.ravel())
    if faces is not None and len(faces):
        faces = np.ascontiguousarray(faces, dtype=np.int32)
        k = len(faces)
        mesh.loops.add(3 * k)
        mesh.loops.foreach_set("vertex_index", faces.ravel())
        mesh.polygons.add(k)
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * k, 3, dtype=np.int32))
        mesh.polygons.foreach_set("loop_total", np.full(k, 3, dtype=np.int32))
    mesh.update()
    return mesh


def _sequences(scene_dict):
    """What a live run shows, as (sequence name, object, kind): each object's
    particles, its skin when it has one, its triangulation when the scene's
    outputs ask for one (the sequences a run's frames hold, tools aside)."""
    surfaces = scene_dict.get("outputs", {}).get("triangulation", False)
    for o in scene_dict["objects"]:
        yield o["name"], o["name"], "particles"
        if o.get("skin"):
            yield o["name"] + "_skin", o["name"], "skin"
        if surfaces:
            yield o["name"] + "_surface", o["name"], "surface"


def run_scene(scene, frames=None, threads=None, collection_name=None):
    """Runs a scene inside Blender with the `oriented_particles` package
    (README "Python": Blender's Python must find it and numpy) and builds
    its animated objects from the simulation's arrays, no file in between:
    one object per sequence (each object's particles, skin and
    triangulation), its mesh swapped on every frame change as for an
    imported run. Opsim frame k is Blender frame k, at the scene's frame
    rate; coordinates are the scene's (z-up, Blender's +Z up).

    `scene` is a scene file (.ron, .json) or an `oriented_particles.Scene`;
    `frames` the number of frames (default: the scene's duration);
    `threads` the simulation's threads. Returns the created objects.
    """
    import oriented_particles as op

    if not isinstance(scene, op.Scene):
        scene = op.Scene.load(scene)
    sim = scene.build(threads=threads)
    rate = sim.frame_rate
    if frames is None:
        frames = int(round(sim.duration * rate)) + 1
    sequences = list(_sequences(scene.to_dict()))
    names = {seq: [] for seq, _, _ in sequences}
    for k in range(frames):
        sim.advance(k / rate)
        for seq, obj, kind in sequences:
            if kind == "particles":
                mesh = _mesh_from_arrays("%s.%05d" % (seq, k), sim.positions(obj))
            elif kind == "skin":
                mesh = _mesh_from_arrays("%s.%05d" % (seq, k), *sim.skin_mesh(obj))
            else:
                mesh = _mesh_from_arrays("%s.%05d" % (seq, k), *sim.surface_mesh(obj))
            # Meshes shown by no object would be dropped on saving.
            mesh.use_fake_user = True
            names[seq].append(mesh.name)
    bl_scene = bpy.context.scene
    collection = bpy.data.collections.new(collection_name or scene.name)
    bl_scene.collection.children.link(collection)
    created = []
    for seq, _, kind in sequences:
        ob = bpy.data.objects.new(seq, bpy.data.meshes[names[seq][0]])
        ob[FRAMES_KEY] = names[seq]
        ob["opsim_kind"] = kind
        collection.objects.link(ob)
        created.append(ob)
    _set_frame_rate(bl_scene, rate)
    bl_scene.frame_start = 0
    bl_scene.frame_end = max(frames - 1, 0)
    if _swap_meshes not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_swap_meshes)
    bl_scene.frame_set(0)
    return created


class ImportOpsimRun(bpy.types.Operator, ImportHelper):
    """Import an opsim run folder (its summary.json) as animated objects"""

    bl_idname = "import_scene.opsim_run"
    bl_label = "Import opsim run"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="summary.json", options={"HIDDEN"})
    frame_format: EnumProperty(
        name="Frames",
        items=[
            ("AUTO", "As written", "OBJ if the run wrote it, else PLY"),
            ("obj", "OBJ", "The y-up OBJ frames"),
            ("ply", "PLY", "The binary PLY frames"),
        ],
        default="AUTO",
    )

    def execute(self, context):
        fmt = None if self.frame_format == "AUTO" else self.frame_format
        try:
            objs = import_run(self.filepath, fmt)
        except (OSError, ValueError, KeyError) as e:
            self.report({"ERROR"}, "opsim run: %s" % e)
            return {"CANCELLED"}
        self.report({"INFO"}, "opsim run: %d objects" % len(objs))
        return {"FINISHED"}


class RunOpsimScene(bpy.types.Operator, ImportHelper):
    """Run an opsim scene file inside Blender (the oriented_particles package) as animated objects"""

    bl_idname = "import_scene.opsim_scene"
    bl_label = "Run opsim scene"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".ron"
    filter_glob: StringProperty(default="*.ron;*.json", options={"HIDDEN"})

    def execute(self, context):
        try:
            objs = run_scene(self.filepath)
        except ImportError as e:
            self.report(
                {"ERROR"},
                "opsim scene: the oriented_particles package is not importable from "
                "Blender's Python (README \"Python\", Blender): %s" % e,
            )
            return {"CANCELLED"}
        except (OSError, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, "opsim scene: %s" % e)
            return {"CANCELLED"}
        self.report({"INFO"}, "opsim scene: %d objects" % len(objs))
        return {"FINISHED"}


def _menu(self, _context):
    self.layout.operator(ImportOpsimRun.bl_idname, text="opsim run (summary.json)")
    self.layout.operator(RunOpsimScene.bl_idname, text="opsim scene (run in Blender)")


def register():
    bpy.utils.register_class(ImportOpsimRun)
    bpy.utils.register_class(RunOpsimScene)
    bpy.types.TOPBAR_MT_file_import.append(_menu)
    if _swap_meshes not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_swap_meshes)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    bpy.utils.unregister_class(RunOpsimScene)
    bpy.utils.unregister_class(ImportOpsimRun)
    if _swap_meshes in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(_swap_meshes)


if __name__ == "__main__":
    register()

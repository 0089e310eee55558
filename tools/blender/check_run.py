# SPDX-License-Identifier: MIT OR Apache-2.0
"""Headless check of opsim runs in Blender (used by tests/blender.rs).

    blender -b --factory-startup --python tools/blender/check_run.py -- RUN@K,K... ...

For each run folder RUN and each listed frame K, imports every sequence's
OBJ file alone with Blender's OBJ importer (`wm.obj_import`, and the legacy
`import_scene.obj` when this Blender has it) and, when the run wrote PLY,
its PLY file with Blender's PLY importer; then imports the whole run with
the add-on (opsim_import.py, beside this file), from its OBJ and its PLY
frames, and steps to each listed frame. Prints one line `OPSIM-CHECK {json}` per run with, per
importer, frame and object: vertex, edge and face counts and the
world-space bounds of the vertices.
"""

import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import opsim_import  # noqa: E402


def describe(ob):
    mesh = ob.data
    world = [ob.matrix_world @ v.co for v in mesh.vertices]
    lo = [min((p[i] for p in world), default=0.0) for i in range(3)]
    hi = [max((p[i] for p in world), default=0.0) for i in range(3)]
    return {
        "vertices": len(mesh.vertices),
        "edges": len(mesh.edges),
        "faces": len(mesh.polygons),
        "min": lo,
        "max": hi,
    }


def clear():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for c in list(bpy.data.collections):
        bpy.data.collections.remove(c)


def check(run, frames):
    with open(os.path.join(run, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    sequences = summary["files"]["sequences"]
    importers = {"obj_import": ("obj", lambda p: bpy.ops.wm.obj_import(filepath=p))}
    if opsim_import.has_operator("import_scene", "obj"):
        importers["legacy"] = ("obj", lambda p: bpy.ops.import_scene.obj(filepath=p))
    if "ply" in summary["files"]["formats"]:
        importers["ply"] = ("ply", opsim_import._import_ply)
    result = {"run": run}
    for name, (ext, importer) in importers.items():
        for k in frames:
            for seq in sequences:
                clear()
                path = os.path.join(
                    run, "frames", seq["stem"], "%s_%05d.%s" % (seq["stem"], k, ext)
                )
                importer(path)
                objects = [describe(ob) for ob in bpy.data.objects if ob.type == "MESH"]
                result.setdefault(name, {}).setdefault(str(k), {})[seq["name"]] = objects
    for fmt in ("obj", "ply"):
        if fmt not in summary["files"]["formats"]:
            continue
        clear()
        created = opsim_import.import_run(run, fmt)
        scene = bpy.context.scene
        key = "addon" if fmt == "obj" else "addon_" + fmt
        result[key + "_scene"] = {
            "fps": scene.render.fps / scene.render.fps_base,
            "frame_start": scene.frame_start,
            "frame_end": scene.frame_end,
            "objects": [ob.name for ob in created],
        }
        for k in frames:
            scene.frame_set(k)
            result.setdefault(key, {})[str(k)] = {
                ob.name: [describe(ob)] for ob in created
            }
    clear()
    print("OPSIM-CHECK " + json.dumps(result), flush=True)


def main():
    for arg in sys.argv[sys.argv.index("--") + 1 :]:
        run, _, frames = arg.rpartition("@")
        check(run, [int(k) for k in frames.split(",")])


main()

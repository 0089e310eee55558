"""Run inside Blender by test_usd.py: imports a USD file with Blender's USD
importer (`wm.usd_import`) and writes, for each object it made, its vertex
and face counts at the chosen frames (evaluated: the importer animates
time-sampled meshes with a cache modifier), as JSON; `usd_import` is false
when this Blender has no USD importer (a build without USD, as Debian's).

blender -b --factory-startup --python usd_blender_check.py -- USD FRAMES REPORT
"""

import json
import sys

import bpy

usd, frames, report = sys.argv[sys.argv.index("--") + 1 :]
frames = [int(k) for k in frames.split(",")]
if "usd_import" not in dir(bpy.ops.wm):
    with open(report, "w", encoding="utf-8") as f:
        json.dump({"usd_import": False}, f)
    sys.exit(0)
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob)
result = bpy.ops.wm.usd_import(filepath=usd)
assert result == {"FINISHED"}, result
scene = bpy.context.scene
out = {
    "usd_import": True,
    "fps": scene.render.fps / scene.render.fps_base,
    "frame_start": scene.frame_start,
    "frame_end": scene.frame_end,
    "objects": {},
    "types": {},
}
for ob in bpy.data.objects:
    out["types"][ob.name] = ob.type
for k in frames:
    scene.frame_set(k)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for ob in bpy.data.objects:
        if ob.type != "MESH":
            continue
        evaluated = ob.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        counts = {"vertices": len(mesh.vertices), "faces": len(mesh.polygons)}
        evaluated.to_mesh_clear()
        out["objects"].setdefault(ob.name, {})[str(k)] = counts
with open(report, "w", encoding="utf-8") as f:
    json.dump(out, f)

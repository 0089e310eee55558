"""Run inside Blender by test_blender.py: runs a scene with the add-on's
`run_scene` (tools/blender/opsim_import.py) and writes what it built as JSON.

blender -b --factory-startup --python blender_check.py -- REPO SCENE FRAMES REPORT
"""

import json
import sys

import bpy

repo, scene, frames, report = sys.argv[sys.argv.index("--") + 1 :]
sys.path.insert(0, repo + "/tools/blender")
import opsim_import  # noqa: E402

opsim_import.register()
created = opsim_import.run_scene(scene, frames=int(frames), threads=2)
out = {"objects": {}, "fps": bpy.context.scene.render.fps / bpy.context.scene.render.fps_base}
for ob in created:
    frames_of = []
    for k in range(int(frames)):
        bpy.context.scene.frame_set(k)
        mesh = ob.data
        frames_of.append(
            {
                "mesh": mesh.name,
                "vertices": [list(v.co) for v in mesh.vertices],
                "faces": len(mesh.polygons),
            }
        )
    out["objects"][ob.name] = {"kind": ob["opsim_kind"], "frames": frames_of}
with open(report, "w", encoding="utf-8") as f:
    json.dump(out, f)

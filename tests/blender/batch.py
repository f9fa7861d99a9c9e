"""Runs several renders of exported Blender scripts in one Python process (tests/export_blender.rs):
bpy's start-up is paid once. Argument: a JSON file, a list of jobs:

    {"script": P.py, "args": [...], "fault": ""}   the exported script's main(args), with
                                                   BRDF_SHOP_BLENDER_FAULT set to `fault`
    {"open": M.blend, "out": I.exr}                renders a saved .blend as it is (RGB; alpha 1)

Prints one line per job: `JOB k EXIT seconds CPU-seconds-so-far` (the process's, all threads).
"""

import importlib.util
import json
import os
import sys
import time

import bpy


def render_blend(path, out):
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.render.filepath = out
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    return 0


def main():
    jobs = json.load(open(sys.argv[1]))
    for k, job in enumerate(jobs):
        t = time.time()
        if "open" in job:
            code = render_blend(job["open"], job["out"])
        else:
            os.environ["BRDF_SHOP_BLENDER_FAULT"] = job.get("fault", "")
            spec = importlib.util.spec_from_file_location("exported_%d" % k, job["script"])
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            code = module.main(job["args"])
        print("JOB %d %d %.2f %.2f" % (k, code, time.time() - t, time.process_time()), flush=True)


if __name__ == "__main__":
    main()

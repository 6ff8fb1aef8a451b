"""Render the open scene once: a multilayer EXR (every pass) and a PNG preview.

    BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b blend_samples/showcase.blend \
        --addons deferred_render -E DEFERRED_RENDER \
        --python blend_samples/render_sample.py -- OUT/showcase [--samples N] [--percentage P]

writes OUT/showcase.exr (32-bit multilayer, scene-linear, all registered
passes) and OUT/showcase.png (Combined through the scene's view transform,
as Blender shows it). Same result as

    ... -o OUT/showcase_ -F OPEN_EXR_MULTILAYER -f 1

plus the preview, without rendering twice.
"""

import argparse
import os
import sys

import bpy


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_sample.py")
    parser.add_argument("output", help="output path without extension")
    parser.add_argument("--samples", type=int, default=None, help="override scene.deferred_render.samples")
    parser.add_argument("--percentage", type=int, default=None, help="override the resolution percentage")
    args = parser.parse_args(argv)

    scene = bpy.context.scene
    if args.samples is not None and hasattr(scene, "deferred_render"):
        scene.deferred_render.samples = args.samples
    if args.percentage is not None:
        scene.render.resolution_percentage = args.percentage
    # Every pass the engine produces: the flags saved in the samples, plus
    # the passes added since they were generated (Shadow, AO).
    for layer in scene.view_layers:
        layer.use_pass_shadow = True
        layer.use_pass_ambient_occlusion = True
    out = os.path.abspath(args.output)
    os.makedirs(os.path.dirname(out), exist_ok=True)

    img = scene.render.image_settings
    img.file_format = 'OPEN_EXR_MULTILAYER'
    img.color_depth = '32'
    img.exr_codec = 'ZIP'
    scene.render.use_file_extension = True
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)

    img.file_format = 'PNG'
    img.color_mode = 'RGBA'
    img.color_depth = '8'
    bpy.data.images["Render Result"].save_render(out + ".png", scene=scene)
    print(f"render_sample: wrote {out}.exr and {out}.png")


main()

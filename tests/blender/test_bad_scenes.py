"""Bad scenes end with a clear message or the documented fallback, never a crash.

In this Blender process (analytic scene), each case is rendered with F12:

| case                         | expected                                               |
| ---------------------------- | ------------------------------------------------------ |
| mesh object without faces    | skipped, warning names it, render succeeds            |
| mesh with NaN coordinates    | skipped, warning names it, the rest renders            |
| object with NaN transform    | skipped, warning names it                              |
| area light of size 0         | skipped with a warning; radius-0 point light renders   |
| NaN material input           | sanitized, finite image                                 |
| no camera                    | Blender's own "Cannot render, no camera" error         |
| non-camera object as camera  | error "... is not a camera object"                     |
| resolution beyond the GPU    | error naming the limit; the next render works again    |

Then the same error cases run as `blender -b ... -f 1` subprocesses: Blender
must exit through its normal path (exit code 0 for fallbacks, 1 for errors,
as it does for Cycles' errors), print the message, and not crash.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_bad_scenes.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render.engine import final  # noqa: E402


def render(out, name):
    """F12 to EXR; returns (error message or None, channels or None, messages)."""
    final.last_messages.clear()
    try:
        path = U.render_exr(os.path.join(out, name))
    except RuntimeError as ex:
        return str(ex), None, list(final.last_messages)
    return None, U.read_exr(path), list(final.last_messages)


def messages_text(messages):
    return " | ".join(m for _, m in messages)


def link_mesh(name, verts, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def test_fallbacks(checks, out):
    scene = bpy.context.scene
    empty = link_mesh("EmptyMesh", [], [])
    nan = link_mesh("NaNMesh", [(0, -6, 1), (float("nan"), -6, 2), (1, -6, 2)], [(0, 1, 2)])
    nan_matrix = link_mesh("NaNMatrix", [(0, 0, 0), (1, 0, 0), (1, 1, 0)], [(0, 1, 2)])
    nan_matrix.location = (float("nan"), 0, 0)
    zero_area = bpy.data.lights.new("ZeroArea", 'AREA')
    zero_area.size = 0.0
    zero_area.energy = 100
    zero_ob = bpy.data.objects.new("ZeroArea", zero_area)
    zero_ob.location = (0, -3, 3)
    scene.collection.objects.link(zero_ob)
    hard = bpy.data.lights.new("HardPoint", 'POINT')
    hard.shadow_soft_size = 0.0
    hard.energy = 50
    hard_ob = bpy.data.objects.new("HardPoint", hard)
    hard_ob.location = (0, -4, 0.05)   # 5 cm above the floor
    scene.collection.objects.link(hard_ob)
    bsdf = bpy.data.materials["MatFloor"].node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = float("nan")

    error, ch, messages = render(out, "fallbacks")
    text = messages_text(messages)
    checks.check(error is None, "fallback scene renders", error or "")
    checks.check("'EmptyMesh'" in text and "no faces" in text, "empty mesh: skipped with a warning naming it")
    checks.check("'NaNMesh'" in text and "NaN" in text, "NaN coordinates: skipped with a warning naming it")
    checks.check("'NaNMatrix'" in text, "NaN transform: skipped with a warning naming it")
    checks.check("ZeroArea" in text and "zero size" in text, "zero-size area light: skipped with a warning")
    if ch is not None:
        values = np.stack([ch[f"ViewLayer.Combined.{c}"] for c in "RGBA"], -1)
        checks.check(np.isfinite(values).all(), "image finite (radius-0 light near a surface, NaN roughness)")
        checks.check(4 in np.unique(ch["ViewLayer.IndexOB.X"]), "the rest of the scene still renders")
    print("  messages:", text)
    for obj in (empty, nan, nan_matrix, zero_ob, hard_ob):
        bpy.data.objects.remove(obj)
    bsdf.inputs["Roughness"].default_value = 0.5


def test_errors(checks, out):
    scene = bpy.context.scene
    camera = scene.camera

    scene.camera = None
    error, _, _ = render(out, "nocamera")
    checks.check(error is not None and "camera" in error.lower(), "no camera: clear error", error or "no error")
    scene.camera = bpy.data.objects["Point"]
    error, _, _ = render(out, "lightcamera")
    checks.check(error is not None and "not a camera" in error, "light as camera: clear error", error or "no error")
    scene.camera = camera

    render_settings = scene.render
    size = render_settings.resolution_x, render_settings.resolution_y, render_settings.resolution_percentage
    render_settings.resolution_x, render_settings.resolution_y, render_settings.resolution_percentage = 40000, 8, 100
    error, _, _ = render(out, "huge")
    checks.check(error is not None and "Deferred" in error and "40000" in error,
                 "resolution beyond the GPU: error names the size and limit", error or "no error")
    render_settings.resolution_x, render_settings.resolution_y, render_settings.resolution_percentage = size
    error, ch, _ = render(out, "after_error")
    checks.check(error is None and ch is not None, "the next render after an error works", error or "")


def test_command_line(checks, out):
    blend = os.path.join(U.SAMPLES, "analytic.blend")
    cases = (
        ("no camera", "import bpy; bpy.context.scene.camera = None", 1, "no camera"),
        ("light as camera", "import bpy; s = bpy.context.scene; s.camera = bpy.data.objects['Point']", 1,
         "not a camera object"),
        ("resolution beyond the GPU", "import bpy; r = bpy.context.scene.render; "
         "r.resolution_x, r.resolution_y, r.resolution_percentage = 40000, 8, 100", 1, "exceeds"),
        ("empty mesh", "import bpy; m = bpy.data.meshes.new('E'); "
         "bpy.context.scene.collection.objects.link(bpy.data.objects.new('EmptyMesh', m)); "
         "bpy.context.scene.deferred_render.samples = 1", 0, "'EmptyMesh' skipped"),
    )
    for label, expr, code_expected, text in cases:
        cmd = U.blender_command(blend, "--python-expr", expr, "-o", os.path.join(out, "cli_"),
                                "-F", "OPEN_EXR_MULTILAYER", "-f", "1")
        code, output = U.run_blender(cmd, timeout=300)
        crashed = code < 0 or "Segmentation fault" in output or "crash" in output.lower()
        checks.check(code == code_expected and not crashed and text in output and "Blender quit" in output,
                     f"command line, {label}: exit {code_expected}, message printed, normal shutdown",
                     f"exit {code}; " + " | ".join(l for l in output.splitlines() if text in l)[:200])


def main():
    checks = U.Checks("test_bad_scenes")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    scene.render.resolution_percentage = 50
    scene.deferred_render.samples = 1
    out = U.out_dir("bad_scenes")
    checks.run("fallbacks", test_fallbacks, checks, out)
    checks.run("errors", test_errors, checks, out)
    checks.run("command line", test_command_line, checks, out)
    checks.finish()


main()

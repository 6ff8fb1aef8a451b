"""Without the compiled module the add-on still registers and explains itself.

Run WITHOUT --addons: the script blocks the import of
deferred_render.deferred_native (as if it were not built, or built for
another Python), then enables the add-on itself.

    BLENDER_USER_SCRIPTS=<build>/blender_scripts blender -b --factory-startup \
        blend_samples/analytic.blend --python-exit-code 1 --python tests/blender/test_native_missing.py
"""

import os
import sys

sys.modules["deferred_render.deferred_native"] = None  # import now raises ImportError

import addon_utils  # noqa: E402
import bpy  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402


def main():
    checks = U.Checks("test_native_missing")
    mod = addon_utils.enable("deferred_render", default_set=True, handle_error=None)
    checks.check(mod is not None, "add-on enables without the native module")
    scene = bpy.context.scene
    scene.render.engine = "DEFERRED_RENDER"
    checks.check(scene.render.engine == "DEFERRED_RENDER", "engine registered and selectable")

    from deferred_render import native
    checks.check(native.try_load() is None and "could not be imported" in (native.error_message() or ""),
                 "native.try_load() reports the failure", native.error_message() or "")

    U.set_all_passes(scene.view_layers[0], True)
    scene.use_nodes = True
    rl = scene.node_tree.nodes.new("CompositorNodeRLayers")
    rl.update()
    outputs = [s.name for s in rl.outputs if s.enabled]
    checks.check(outputs == ["Image", "Alpha"], "only Combined is registered", str(outputs))

    scene.render.resolution_percentage = 25
    error = None
    try:
        bpy.ops.render.render()
    except RuntimeError as ex:
        error = str(ex)
    checks.check(error is not None and "could not be imported" in error and "cmake" in error,
                 "render reports a clear error with the build hint", (error or "no error").strip())
    result = bpy.data.images.get("Render Result")
    checks.check(result is not None, "Blender still has a (empty) render result")
    # A failed render leaves Blender's exit code at 1 until the next render
    # succeeds (Blender's own behaviour, also for "no camera"): render once
    # with Workbench, which also shows the session is still usable.
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.render.resolution_percentage = 10
    bpy.ops.render.render()
    checks.check(True, "another engine renders afterwards in the same session")
    checks.finish()


main()

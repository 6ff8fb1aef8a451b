"""Bad input through real Blender (issue 7): a clear error or the documented
fallback, Blender goes on, nothing written half.

| case                                                  | expected                                           |
| ----------------------------------------------------- | -------------------------------------------------- |
| object without any material slot                      | default surface, renders                           |
| Image Texture on a missing file, node group, Volume   | one warning naming the material, renders           |
| Specular 20 / Base Color 1e6 through Value/RGB nodes   | clamped to 12 / 65504, noted in the warning        |
| object scaled to 1e20, vertices at 1e16               | skipped, warning "beyond 1e+15"                    |
| light at 1e13 W                                       | skipped, warning names the limit                   |
| area light 1e-9 m, point light radius 1e-20           | rendered (native fallbacks), finite                |
| world strength 1e13, mist start NaN                   | clamped / default, finite                          |
| render cancelled at every stage                       | no error, Blender goes on, next render works       |
| EGL device 999 (scene setting)                        | error naming the device; EEVEE and the next render |
|                                                       | still work                                         |
| blender -b -f 1 with device 999 / no EGL vendor at all| message, exit 1, normal shutdown, no file written  |

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/robustness/blender_bad_input.py
"""

import math
import os
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "blender"))
import blender_test_utils as U  # noqa: E402

from deferred_render.engine import final  # noqa: E402


def render(out, name):
    """F12 to EXR; returns (error or None, channels or None, messages, path)."""
    final.last_messages.clear()
    path = os.path.join(out, name + ".exr")
    if os.path.exists(path):
        os.remove(path)
    try:
        U.render_exr(os.path.join(out, name))
    except RuntimeError as ex:
        return str(ex), None, list(final.last_messages), path
    channels = U.read_exr(path) if os.path.exists(path) else None
    return None, channels, list(final.last_messages), path


def text(messages):
    return " | ".join(m for _, m in messages)


def all_finite(channels):
    bad = [name for name, values in channels.items() if not np.isfinite(values).all()]
    return not bad, bad


def link_mesh(name, verts, faces, location=(0, 0, 0), material=None):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    if material is not None:
        mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def link_light(name, kind, location, **props):
    light = bpy.data.lights.new(name, kind)
    for key, value in props.items():
        setattr(light, key, value)
    obj = bpy.data.objects.new(name, light)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def material(name, setup):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    tree = mat.node_tree
    setup(tree, tree.nodes["Principled BSDF"])
    return mat


def test_fallbacks(checks, out):
    scene = bpy.context.scene
    quad = [(-0.4, -0.4, 0), (0.4, -0.4, 0), (0.4, 0.4, 0), (-0.4, 0.4, 0)]
    created = []

    def missing_image(tree, bsdf):
        tex = tree.nodes.new("ShaderNodeTexImage")
        image = bpy.data.images.new("MissingTexture", 8, 8)
        image.source = 'FILE'
        image.filepath = "/nonexistent/missing_texture.png"
        tex.image = image
        tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])

    def node_group(tree, bsdf):
        group = bpy.data.node_groups.new("RobustGroup", "ShaderNodeTree")
        group.outputs.new("NodeSocketShader", "Shader")
        inner_out = group.nodes.new("NodeGroupOutput")
        inner_bsdf = group.nodes.new("ShaderNodeBsdfDiffuse")
        group.links.new(inner_bsdf.outputs[0], inner_out.inputs[0])
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        tree.links.new(node.outputs[0], tree.nodes["Material Output"].inputs["Surface"])

    def volume_only(tree, bsdf):
        out_node = tree.nodes["Material Output"]
        tree.links.remove(out_node.inputs["Surface"].links[0])
        vol = tree.nodes.new("ShaderNodeVolumePrincipled")
        tree.links.new(vol.outputs[0], out_node.inputs["Volume"])

    def huge_values(tree, bsdf):
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 20.0
        tree.links.new(value.outputs[0], bsdf.inputs["Specular"])
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = (1e6, 0.5, 0.5, 1.0)
        tree.links.new(rgb.outputs[0], bsdf.inputs["Base Color"])

    mats = {name: material(name, setup) for name, setup in (
        ("MissingImage", missing_image), ("GroupNode", node_group), ("VolumeOnly", volume_only),
        ("HugeValues", huge_values))}
    for k, (name, mat) in enumerate(mats.items()):
        created.append(link_mesh(f"Obj{name}", quad, [(0, 1, 2, 3)], location=(-1.5 + k, -2.5, 0.3), material=mat))
    no_material = link_mesh("NoMaterial", quad, [(0, 1, 2, 3)], location=(2.5, -2.5, 0.3))
    no_material.pass_index = 77
    created.append(no_material)
    huge_scale = link_mesh("HugeScale", quad, [(0, 1, 2, 3)], location=(0, -3, 1))
    huge_scale.scale = (1e20, 1e20, 1e20)
    created.append(huge_scale)
    far_verts = link_mesh("FarVerts", [(1e16, 0, 0), (1e16 + 1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
    created.append(far_verts)
    created.append(link_light("Blinding", "POINT", (0, -2, 2), energy=1e13))
    created.append(link_light("TinyArea", "AREA", (0.5, -2.5, 1.0), energy=50.0, size=1e-9))
    created.append(link_light("TinySphere", "POINT", (-0.5, -2.5, 1.0), energy=50.0, shadow_soft_size=1e-20))
    # World colour x strength 1e13 (an RGB node drives the colour: the
    # Strength socket itself stops at 1e6).
    world = scene.world
    background = world.node_tree.nodes.get("Background") if world and world.use_nodes else None
    old_strength = background.inputs["Strength"].default_value if background else None
    rgb = None
    if background:
        background.inputs["Strength"].default_value = 1e6
        rgb = world.node_tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = (1e7, 1e7, 1e7, 1.0)
        world.node_tree.links.new(rgb.outputs[0], background.inputs["Color"])
    old_mist = world.mist_settings.start if world else None
    if world:
        world.mist_settings.start = float("nan")
    nan_mist = world is not None and math.isnan(world.mist_settings.start)

    error, ch, messages, _ = render(out, "fallbacks")
    t = text(messages)
    checks.check(error is None, "fallback scene renders", error or "")
    checks.check("missing_texture.png" in t and "magenta" in t,
                 "missing image file: one warning names the file, rendered magenta as in Cycles")
    checks.check("'GroupNode'" not in t, "node group material: rendered through the group, no warning")
    checks.check("'VolumeOnly'" in t, "volume-only material: warning names the material")
    checks.check("Specular 20 clamped to 12" in t and "Base Color above 65504 clamped" in t,
                 "out-of-range node values: clamped to the renderer's limits, noted")
    checks.check("'HugeScale' skipped" in t and "beyond 1e+15" in t, "object scaled to 1e20: skipped with a warning")
    checks.check("'FarVerts' skipped" in t and "beyond 1e+15" in t, "vertices at 1e16: skipped with a warning")
    checks.check("'Blinding'" in t and "limit" in t, "1e13 W light: skipped with a warning naming the limit")
    if background:
        checks.check("clamped to 1e+12" in t, "world strength 1e13: clamped with a warning")
    if ch is not None:
        ok, bad = all_finite(ch)
        checks.check(ok, "every pass finite (tiny lights, NaN mist%s)" % (" set" if nan_mist else " not settable"),
                     ", ".join(bad[:5]))
        ids = np.unique(ch["ViewLayer.IndexOB.X"])
        checks.check(77 in ids, "object without materials renders (default surface)", f"IndexOB values {ids[:12]}")
    print("  messages:", t)
    for obj in created:
        bpy.data.objects.remove(obj)
    for mat in mats.values():
        bpy.data.materials.remove(mat)
    if background:
        background.inputs["Strength"].default_value = old_strength
        world.node_tree.nodes.remove(rgb)
    if world:
        world.mist_settings.start = old_mist


def test_cancel(checks, out):
    """The engine's test_break() answers True from its n-th poll on (through
    FinalRender.check_break and the export walk's test_break), for n = 1, 2,
    ...: every stage of the render gets cancelled once. No error, Blender
    goes on. (RNA functions cannot be overridden on the engine class, so the
    add-on's two polling points are patched. A real cancel also sets
    Blender's G.is_break, which stops Blender from writing the cancelled
    result; this simulation cannot, so it renders without writing: Blender
    3.4 would hand the never-merged result to OpenEXR. The real thing, Ctrl+C
    during `blender -b -f`, is test_command_line's SIGINT case.)"""
    original_check, original_export = final.FinalRender.check_break, final.export_scene
    stages = 0
    try:
        for n in range(1, 12):
            calls = {"n": 0}

            def poll(n=n, calls=calls):
                calls["n"] += 1
                return calls["n"] >= n

            def check_break(self):
                if poll():
                    raise final.RenderCancelled()

            def export_scene(depsgraph, renderer, warn=None, test_break=None, **kwargs):
                return original_export(depsgraph, renderer, warn=warn, test_break=poll, **kwargs)

            final.FinalRender.check_break = check_break
            final.export_scene = export_scene
            final.last_messages.clear()
            error = None
            try:
                bpy.ops.render.render(write_still=False)
            except RuntimeError as ex:
                error = str(ex)
            errors = [m for level, m in final.last_messages if level == 'ERROR']
            if calls["n"] < n:  # finished before the n-th poll: every stage was covered
                checks.check(error is None and not errors, f"{calls['n']} polls: the render completes")
                break
            stages += 1
            checks.check(error is None and not errors, f"cancelled at poll {n}: no error, no crash",
                         f"error {error}; errors {errors}")
    finally:
        final.FinalRender.check_break, final.export_scene = original_check, original_export
    checks.check(stages >= 3, f"cancelled at {stages} different stages")
    error, ch, _, _ = render(out, "after_cancel")
    checks.check(error is None and ch is not None, "the next render after cancelling works", error or "")


def test_device_error(checks, out):
    scene = bpy.context.scene
    settings = scene.deferred_render
    settings.device_index = 999 if settings.bl_rna.properties["device_index"].hard_max >= 999 else 64
    bad = settings.device_index
    error, ch, messages, path = render(out, "bad_device")
    checks.check(error is not None and f"EGL device {bad}" in error, "bad EGL device: clear error naming it",
                 error or "no error")
    settings.device_index = -1
    error, ch, _, _ = render(out, "good_device")
    checks.check(error is None and ch is not None, "the next render with the automatic device works", error or "")
    # Blender's own GL keeps working.
    scene.render.engine = 'BLENDER_EEVEE'
    try:
        error, ch, _, _ = render(out, "eevee_after")
        checks.check(error is None and ch is not None, "EEVEE renders in the same process afterwards", error or "")
    finally:
        scene.render.engine = U.ENGINE


def test_command_line(checks, out):
    blend = os.path.join(U.SAMPLES, "analytic.blend")
    cases = (
        ("EGL device 64", "import bpy; bpy.context.scene.deferred_render.device_index = 64", {}, "EGL device 64"),
        ("no EGL vendor library", "", {"__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"}, "Deferred: "),
        ("bad DEFERRED_EGL_DEVICE", "", {"DEFERRED_EGL_DEVICE": "gpu0"}, "DEFERRED_EGL_DEVICE='gpu0'"),
    )
    for label, expr, env_extra, needle in cases:
        prefix = os.path.join(out, "cli_" + label.replace(" ", "_") + "_")
        for ext in ("0001.exr",):
            if os.path.exists(prefix + ext):
                os.remove(prefix + ext)
        args = (["--python-expr", expr] if expr else []) + ["-o", prefix, "-F", "OPEN_EXR_MULTILAYER", "-f", "1"]
        cmd = U.blender_command(blend, *args)
        env = dict(os.environ, **env_extra)
        import subprocess
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300, env=env)
        output = proc.stdout.decode("utf-8", "replace")
        code = proc.returncode
        crashed = code < 0 or "Segmentation fault" in output or "Traceback" in output
        written = os.path.exists(prefix + "0001.exr")
        line = " | ".join(l for l in output.splitlines() if needle in l)[:240]
        checks.check(code == 1 and not crashed and needle in output and "Blender quit" in output and not written,
                     f"command line, {label}: message, exit 1, normal shutdown, no file written",
                     f"exit {code}; file {'WRITTEN' if written else 'not written'}; {line}")


def test_ctrl_c(checks, out):
    """A real cancel: SIGINT (Ctrl+C) to `blender -b -f 1` at each stage.
    Blender turns the first Ctrl+C into its break flag; the add-on polls it
    between stages. Expect: normal shutdown, exit 1 (Blender's code for a
    cancelled -f), no file written, no crash. The latency is measured: the
    native render call itself is not interruptible."""
    import signal
    import subprocess
    import time
    blend = os.path.join(U.SAMPLES, "showcase.blend")
    expr = "import bpy; s = bpy.context.scene; s.deferred_render.samples = 4; s.render.resolution_percentage = 25"
    for stage in ("starting GL", "exporting scene", "rendering ", "writing passes"):
        prefix = os.path.join(out, "sigint_" + stage.strip().replace(" ", "_") + "_")
        if os.path.exists(prefix + "0001.exr"):
            os.remove(prefix + "0001.exr")
        cmd = U.blender_command(blend, "--python-expr", expr, "-o", prefix, "-F", "OPEN_EXR_MULTILAYER", "-f", "1")
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=dict(os.environ))
        lines, sent = [], None
        for raw in iter(proc.stdout.readline, b""):
            line = raw.decode("utf-8", "replace").rstrip()
            lines.append(line)
            if sent is None and stage in line:
                proc.send_signal(signal.SIGINT)
                sent = time.perf_counter()
        code = proc.wait(timeout=300)
        latency = time.perf_counter() - sent if sent else float("nan")
        output = "\n".join(lines)
        written = os.path.exists(prefix + "0001.exr")
        crashed = code < 0 or "Segmentation fault" in output or "Traceback" in output
        if sent is None:
            checks.check(False, f"Ctrl+C at '{stage}': stage never printed")
            continue
        if written:  # too late: the frame was complete; it must then be whole
            whole = all(np.isfinite(v).all() for v in U.read_exr(prefix + "0001.exr").values())
            checks.check(code == 0 and whole and not crashed, f"Ctrl+C at '{stage}' came after the frame: complete file",
                         f"exit {code}, {latency:.2f} s")
            continue
        checks.check(code == 1 and not crashed and "Blender quit" in output,
                     f"Ctrl+C at '{stage}': normal shutdown, exit 1, nothing written",
                     f"exit {code}, exited {latency:.2f} s after the signal")


def main():
    checks = U.Checks("robustness_blender_bad_input")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    scene.render.resolution_percentage = 25
    scene.deferred_render.samples = 1
    U.set_all_passes(scene.view_layers[0])
    out = U.out_dir("robustness")
    checks.run("fallbacks", test_fallbacks, checks, out)
    checks.run("cancel", test_cancel, checks, out)
    checks.run("device error", test_device_error, checks, out)
    checks.run("command line", test_command_line, checks, out)
    checks.run("ctrl+c", test_ctrl_c, checks, out)
    checks.finish()


main()

"""Engine registration, settings, panels and pass registration.

update_render_passes must register exactly the passes of
deferred_native.PASSES whose view-layer checkbox is on; the compositor's
Render Layers node then shows Image, Alpha and those passes.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_registration.py
"""

import os
import sys
import types

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

# Blender's compositor socket name for each pass ("Combined" shows as Image + Alpha).
SOCKET_NAMES = {"Combined": ("Image", "Alpha")}

# View-layer flags of the passes the renderer may produce.
FLAGS = {
    "Depth": "use_pass_z", "Mist": "use_pass_mist", "Position": "use_pass_position",
    "Normal": "use_pass_normal", "UV": "use_pass_uv", "IndexOB": "use_pass_object_index",
    "IndexMA": "use_pass_material_index", "DiffDir": "use_pass_diffuse_direct",
    "DiffCol": "use_pass_diffuse_color", "GlossDir": "use_pass_glossy_direct",
    "GlossCol": "use_pass_glossy_color", "Emit": "use_pass_emit", "Env": "use_pass_environment",
}
TYPES = {"Depth": "VALUE", "Mist": "VALUE", "IndexOB": "VALUE", "IndexMA": "VALUE",
         "Position": "VECTOR", "Normal": "VECTOR", "UV": "VECTOR", "Vector": "VECTOR"}


def render_layers_outputs(scene):
    scene.use_nodes = True
    tree = scene.node_tree
    node = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers"), None)
    if node is None:
        node = tree.nodes.new("CompositorNodeRLayers")
    node.layer = scene.view_layers[0].name
    node.update()
    return [s.name for s in node.outputs if s.enabled]


def test_engine(checks):
    engine = bpy.types.RenderEngine.bl_rna_get_subclass_py("DEFERRED_RENDER")
    checks.check(engine is not None, "RenderEngine DEFERRED_RENDER registered")
    checks.check(engine.bl_label == "Deferred", "label 'Deferred'")
    checks.check(engine.bl_use_shading_nodes_custom is False, "bl_use_shading_nodes_custom = False")
    checks.check(engine.bl_use_postprocess is True, "bl_use_postprocess = True")
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.engine = "DEFERRED_RENDER"
    checks.check(scene.render.engine == "DEFERRED_RENDER", "engine selectable as scene.render.engine")
    U.require_engine(checks)
    settings = bpy.context.scene.deferred_render
    prop = type(settings).bl_rna.properties
    checks.check(prop["samples"].default == 16 and prop["device_index"].default == -1,
                 "scene.deferred_render: samples 16, device_index -1")


def test_panels(checks):
    ctx = types.SimpleNamespace(engine="DEFERRED_RENDER", scene=bpy.context.scene,
                                light=bpy.data.lights[0], material=bpy.data.materials[0],
                                world=bpy.context.scene.world, object=bpy.data.objects[0])
    for name in ("RENDER_PT_format", "RENDER_PT_frame_range", "RENDER_PT_output", "RENDER_PT_color_management",
                 "VIEWLAYER_PT_layer", "OBJECT_PT_visibility", "DATA_PT_lens", "DATA_PT_camera",
                 "EEVEE_WORLD_PT_surface", "EEVEE_WORLD_PT_mist", "EEVEE_MATERIAL_PT_surface",
                 "EEVEE_MATERIAL_PT_context_material", "DATA_PT_spot"):
        panel = getattr(bpy.types, name)
        checks.check("DEFERRED_RENDER" in panel.COMPAT_ENGINES, f"Blender panel {name} shown for the engine")
    for name in ("DATA_PT_EEVEE_shadow", "RENDER_PT_eevee_sampling", "DATA_PT_light"):
        panel = getattr(bpy.types, name)
        checks.check("DEFERRED_RENDER" not in panel.COMPAT_ENGINES, f"{name} not shown (EEVEE-only or replaced)")
    for name in ("DEFERRED_RENDER_PT_sampling", "DEFERRED_RENDER_PT_film", "DEFERRED_RENDER_PT_passes",
                 "DEFERRED_RENDER_PT_light", "DEFERRED_RENDER_PT_device", "DEFERRED_RENDER_PT_material_settings"):
        panel = getattr(bpy.types, name, None)
        checks.check(panel is not None and panel.poll(ctx), f"own panel {name} registered and polls True")
    other = types.SimpleNamespace(**dict(vars(ctx), engine="CYCLES"))
    checks.check(not bpy.types.DEFERRED_RENDER_PT_sampling.poll(other), "own panels hidden for other engines")

    # Disabling the add-on restores Blender's panels; enabling adds the engine again.
    addon_utils.disable("deferred_render", default_set=True)
    checks.check("DEFERRED_RENDER" not in bpy.types.RENDER_PT_format.COMPAT_ENGINES
                 and getattr(bpy.types, "DEFERRED_RENDER_PT_sampling", None) is None,
                 "unregister removes the engine from COMPAT_ENGINES and its panels")
    addon_utils.enable("deferred_render", default_set=True)
    checks.check("DEFERRED_RENDER" in bpy.types.RENDER_PT_format.COMPAT_ENGINES, "re-register works")
    bpy.context.scene.render.engine = "DEFERRED_RENDER"


def test_passes(checks):
    mod = U.native_module()
    if not checks.check(mod is not None, "native module importable (needed for pass registration)"):
        return
    names = [p[0] for p in mod.PASSES]
    checks.check(names[0] == "Combined" and set(FLAGS) <= set(names),
                 "native PASSES lists Combined and the other passes", str(names))
    scene = bpy.context.scene
    layer = scene.view_layers[0]
    U.set_all_passes(layer, True)
    outputs = render_layers_outputs(scene)
    expected = ["Image", "Alpha"] + [n for n in names if n != "Combined"]
    checks.check(outputs == expected, "all flags on: Render Layers shows Image, Alpha + every native pass",
                 str(outputs))
    U.set_all_passes(layer, False)
    layer.use_pass_z = True
    layer.use_pass_normal = True
    layer.use_pass_vector = True       # produced (from the neighbouring frames): must appear
    layer.use_pass_diffuse_indirect = True  # not produced by the renderer: must not appear
    layer.use_pass_shadow = True       # produced (EEVEE's convention): must appear
    layer.use_pass_ambient_occlusion = True  # produced (world occlusion): must appear
    outputs = render_layers_outputs(scene)
    checks.check(outputs == ["Image", "Alpha", "Depth", "Normal", "Shadow", "AO", "Vector"],
                 "only enabled AND produced passes are registered", str(outputs))
    layer.use_pass_vector = layer.use_pass_shadow = layer.use_pass_ambient_occlusion = False
    layer.use_pass_diffuse_indirect = False

    # The engine's own registration list: channel ids and types as Cycles.
    from deferred_render.engine import passes
    U.set_all_passes(layer, True)
    specs = {s.name: s for s in passes.enabled_passes(layer, mod.PASSES)}
    ok = all(specs[n].type == TYPES.get(n, "COLOR") for n in specs)
    checks.check(ok and specs["Depth"].chan_id == "Z" and specs["Normal"].chan_id == "XYZ"
                 and specs["UV"].chan_id == "UVA" and specs["IndexOB"].chan_id == "X"
                 and specs["Vector"].chan_id == "XYZW",
                 "pass types and channel ids as Cycles registers them")


def main():
    checks = U.Checks("test_registration")
    checks.run("engine", test_engine, checks)
    checks.run("panels", test_panels, checks)
    checks.run("passes", test_passes, checks)
    checks.finish()


main()

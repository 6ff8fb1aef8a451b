"""View layers and film transparent behave as in Cycles.

The analytic scene gets three view layers:
- "ViewLayer": every pass on;
- "Layer2": the collection holding SphereB excluded, only Depth and IndexOB;
- "Unused": use for rendering off;
and film transparent on. It is rendered by Deferred and by Cycles (1 sample,
same scene) to multilayer EXRs, and compared:

- the EXR channel names are the same (same layers, same passes per layer);
- SphereB is absent from Layer2 in both;
- alpha is 0 on the background and 1 on objects in both (premultiplied: the
  background RGB is 0), objects are still lit;
- the alpha masks agree away from edges;
- an object hidden for render (hide_render) does not appear.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_film_view_layers.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402


def setup(scene):
    extras = bpy.data.collections.new("Extras")
    scene.collection.children.link(extras)
    sphere = bpy.data.objects["SphereB"]
    scene.collection.objects.unlink(sphere)
    extras.objects.link(sphere)

    main = scene.view_layers["ViewLayer"]
    U.set_all_passes(main, True)
    layer2 = scene.view_layers.new("Layer2")
    U.set_all_passes(layer2, False)
    layer2.use_pass_z = True
    layer2.use_pass_object_index = True
    layer2.layer_collection.children["Extras"].exclude = True
    unused = scene.view_layers.new("Unused")
    unused.use = False
    scene.render.use_single_layer = False
    scene.render.film_transparent = True
    scene.render.resolution_percentage = 50
    scene.deferred_render.samples = 1
    scene.cycles.samples = 1
    scene.cycles.pixel_filter_type = 'BOX'
    scene.cycles.filter_width = 0.01
    scene.cycles.seed = 0


def render(engine, out):
    scene = bpy.context.scene
    scene.render.engine = engine
    path = U.render_exr(os.path.join(out, engine.lower()))
    return U.read_exr(path)


def layer_passes(channels):
    layers = {}
    for name in channels:
        layer, pas, chan = name.rsplit(".", 2)
        layers.setdefault(layer, set()).add(f"{pas}.{chan}")
    return layers


def main():
    checks = U.Checks("test_film_view_layers")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    setup(scene)
    out = U.out_dir("film_view_layers")
    ours = render("DEFERRED_RENDER", out)
    cycles = render("CYCLES", out)
    scene.render.engine = "DEFERRED_RENDER"

    ours_layers, cycles_layers = layer_passes(ours), layer_passes(cycles)
    checks.check(sorted(ours_layers) == ["Layer2", "ViewLayer"], "layers rendered: ViewLayer, Layer2 (not Unused)",
                 str(sorted(ours_layers)))
    checks.check(sorted(ours_layers) == sorted(cycles_layers), "same layers as Cycles", str(sorted(cycles_layers)))
    for layer in ours_layers:
        a, b = ours_layers[layer], cycles_layers.get(layer, set())
        checks.check(a == b, f"{layer}: same passes and channels as Cycles",
                     f"only ours {sorted(a - b)}, only Cycles {sorted(b - a)}")

    for name, img in (("Deferred", ours), ("Cycles", cycles)):
        ids_main = np.unique(img["ViewLayer.IndexOB.X"])
        ids_l2 = np.unique(img["Layer2.IndexOB.X"])
        checks.check(4 in ids_main and 4 not in ids_l2, f"{name}: SphereB (index 4) excluded from Layer2 only",
                     f"{ids_main} / {ids_l2}")

    index = ours["ViewLayer.IndexOB.X"]
    depth = ours["ViewLayer.Depth.Z"]
    labels = np.where(depth >= 1e9, -1, index)
    interior = U.interior_mask(labels, 1)
    background = interior & (labels == -1)
    objects = interior & (labels > 0)
    alpha = ours["ViewLayer.Combined.A"]
    rgb = np.stack([ours[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
    checks.check(background.sum() > 50 and np.all(alpha[background] == 0), "film transparent: background alpha 0",
                 f"{background.sum()} px")
    checks.check(np.all(alpha[objects] == 1), "objects alpha 1")
    checks.check(np.abs(rgb[background]).max() < 1e-6, "background RGB 0 (premultiplied, as Cycles)")
    checks.check(rgb[objects].mean() > 0.05, "objects still lit", f"mean {rgb[objects].mean():.3f}")
    calpha = cycles["ViewLayer.Combined.A"]
    agree = np.mean((alpha[interior] > 0.5) == (calpha[interior] > 0.5))
    checks.check(agree > 0.99, "alpha mask agrees with Cycles away from edges", f"{100 * agree:.2f} %")
    crgb = np.stack([cycles[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
    checks.check(np.abs(crgb[background]).max() < 1e-6, "Cycles background RGB is 0 too (reference)")

    # Object visibility for render (Object > Visibility > Show in Renders).
    bpy.data.objects["SphereA"].hide_render = True
    hidden = render("DEFERRED_RENDER", out)
    bpy.data.objects["SphereA"].hide_render = False
    ids = np.unique(hidden["ViewLayer.IndexOB.X"])
    checks.check(3 not in ids and 5 in ids, "hide_render object (SphereA, index 3) is not rendered", str(ids))
    checks.finish()


main()

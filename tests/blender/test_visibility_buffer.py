"""The visibility buffer (Render Properties > Device > Visibility Buffer)
against the raster path, through real Blender: the same files rendered both
ways must give the same image, pass by pass.

The visibility buffer writes the G-buffer in compute from the triangle each
pixel sees (native/src/visibility_module.h): the varyings come from the
pixel's ray met on the triangle's plane rather than from the rasteriser's
plane equations, and screen derivatives (Bump) from the neighbours' rays
rather than from the 2x2 quad. So the two paths agree to rounding, except
where a material reads derivatives. The bounds below say how far each may go:
- the data passes: the same surface at the same point, 1e-4 absolute at the
  99.9th percentile (rounding; measured up to 2.4e-5 on the showcase), but
  Normal 2e-3 and the colour passes 1e-3 on materials.blend, whose Voronoi
  bump and image textures read the derivatives and the UVs (measured 4.0e-4
  and 1.3e-4);
- Combined: mean absolute difference 2e-3 of the image's mean, the 99th
  percentile 2 % of it, every pixel 5 % (bump's derivatives, and the
  stochastic choices a pixel's rounded inputs can change at 4 samples;
  measured at most 6.6e-4 where the means are 0.28 to 0.43);
- every pixel of a data pass within 10 times its bound: a wrong object
  (a missed key, a turned-over facing) differs by about 1 however few its
  pixels.
It also checks that the path was really taken (the renderer's timings),
partly transparent materials included (transparency.blend: an image's alpha,
constant alphas, a Transparent BSDF mix).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_visibility_buffer.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("visibility_buffer")
# Passes a material's derivatives reach (Bump), or textures whose lookups
# the UVs' last bits can move to the next texel.
LOOSER = {("materials", "Normal"): 2e-3, ("materials", "DiffCol"): 1e-3, ("materials", "GlossCol"): 1e-3,
          ("materials", "Emit"): 1e-3}
DATA_PASSES = (("Normal", "XYZ"), ("UV", "UVA"), ("IndexOB", "X"), ("IndexMA", "X"), ("DiffCol", "RGB"),
               ("GlossCol", "RGB"), ("Emit", "RGB"), ("Depth", "Z"))


def render(name, visibility, size=(200, 150), samples=4):
    from deferred_render.engine import final
    scene = bpy.context.scene
    scene.render.engine = U.ENGINE
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = samples
    scene.deferred_render.visibility_buffer = visibility
    layer = scene.view_layers[0]
    U.set_all_passes(layer, False)
    layer.use_pass_normal = layer.use_pass_uv = layer.use_pass_z = True
    layer.use_pass_object_index = layer.use_pass_material_index = True
    layer.use_pass_diffuse_color = layer.use_pass_glossy_color = layer.use_pass_emit = True
    channels = U.read_exr(U.render_exr(os.path.join(OUT, f"{name}_{'vis' if visibility else 'raster'}"), scene))
    images = {"Combined": U.exr_pass(channels, "ViewLayer", "Combined", "RGBA").astype(np.float64)}
    for p, letters in DATA_PASSES:
        images[p] = U.exr_pass(channels, "ViewLayer", p, letters).astype(np.float64)
    return images, dict(final.last_timings), U.last_messages()


def compare(name, failures):
    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, name + ".blend"))
    raster, t_raster, _ = render(name, False)
    vis, t_vis, messages = render(name, True)
    if t_raster.get("visibility_buffer") or not t_vis.get("visibility_buffer"):
        failures.append(f"{name}: the path taken (timings' visibility_buffer) is raster {t_raster.get('visibility_buffer')}, "
                        f"visibility {t_vis.get('visibility_buffer')}; messages {messages}")
    rows = []
    for p, _ in DATA_PASSES:
        a, b = raster[p], vis[p]
        if p == "Depth":  # the background's depth is huge: compare where a surface is
            keep = a < 1e9
            a, b = a[keep], b[keep]
        d = np.abs(a - b)
        q = float(np.quantile(d, 0.999)) if d.size else 0.0
        worst = float(d.max()) if d.size else 0.0
        rows.append(f"{name} {p}: max {worst:.3g}, 99.9th percentile {q:.3g}")
        bound = 1e-4 * max(1.0, float(np.abs(a).max())) if p == "Depth" else LOOSER.get((name, p), 1e-4)
        # Every pixel too: a wrong object (a missed key, a flipped facing)
        # is a difference of order 1, however few its pixels.
        if q > bound or worst > 10 * bound or not np.isfinite(b).all():
            failures.append(rows[-1] + f" (bounds {bound:.3g}, every pixel {10 * bound:.3g})")
    a, b = raster["Combined"][..., :3], vis["Combined"][..., :3]
    d = np.abs(a - b)
    mean = max(float(a.mean()), 1e-6)
    rows.append(f"{name} Combined: mean |diff| {d.mean():.3g} ({d.mean() / mean:.2%} of the image mean "
                f"{mean:.3g}), 99th percentile {np.quantile(d, 0.99):.3g}, max {d.max():.3g}")
    if (d.mean() > 2e-3 * mean or np.quantile(d, 0.99) > 0.02 * mean or d.max() > 0.05 * max(mean, 0.1)
            or not np.isfinite(b).all()):
        failures.append(rows[-1])
    # Alpha: the same coverage.
    alpha = np.abs(raster["Combined"][..., 3] - vis["Combined"][..., 3])
    if alpha.max() > 1e-4:
        failures.append(f"{name}: alpha differs by {alpha.max():.3g}")
    for r in rows:
        print(r)


def main():
    failures = []
    # Everyday node materials (image textures through UV and Mapping, a
    # normal map, Voronoi bump, vertex colours, procedurals, Object Info
    # Random, an emissive panel) and the showcase (instances, mirrored and
    # scaled objects, Principled parameters, several lights).
    compare("materials", failures)
    compare("showcase", failures)
    # Stochastic transparency: a leaf cut out by an image's alpha (a node
    # material's own visibility program), panes of constant alpha, a
    # Diffuse mixed with a Transparent BSDF; the same pixels covered.
    compare("transparency", failures)

    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("visibility buffer: OK")


main()

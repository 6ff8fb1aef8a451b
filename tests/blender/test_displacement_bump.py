"""The Material Output's Displacement at Cycles' default Displacement Method,
"Bump Only", against Cycles 3.4.

Cycles does not move the surface there: ShaderGraph::bump_from_displacement
evaluates the displacement graph at P, P + dP.dx and P + dP.dy, takes each
vector's height along the normal into a Bump node (strength 1, distance 1)
and makes its normal the shading normal of the whole surface. Before, the
engine ignored the Displacement and warned "Displacement (not rendered)"
(the bundled materials library's 'Crushed Velvet Eevee' with IOR 1.45 and
no transmission rendered 1.10x Cycles' light, 0.97x without its
Displacement; bench/materials/results/isolate/isolate.md).

A smooth sphere under one area light (blender_test_utils.sphere_in_front),
a grey Principled surface whose Displacement node takes a Noise texture's
height; ours at 256 samples, Cycles at 1024, the sphere's interior pixels.
Checked: the light's sum, and the bump's pattern, ours against Cycles' (the
bumped image minus the flat one; correlation and relative error), in object
and in world space, and for a step height; 'Displacement Only' is warned and leaves the surface
flat (Cycles moves it: not rendered here).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_displacement_bump.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("displacement_bump")


def material(space=None, scale=0.08, method="BUMP", step=False):
    """Principled grey, roughness 0.4; with ``space`` a Displacement of a
    Noise texture (Generated coordinates, scale 6) of that space; ``step``:
    of the noise's step at 0.5 (a height whose bump depends on the offsets'
    length, where P and P + dP straddle an edge)."""
    mat = bpy.data.materials.new(f"disp_{len(bpy.data.materials)}")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.6, 0.6, 0.6, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.4
    if space is not None:
        noise = nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = 6.0
        noise.inputs["Detail"].default_value = 2.0
        disp = nodes.new("ShaderNodeDisplacement")
        disp.space = space
        disp.inputs["Scale"].default_value = scale
        height = noise.outputs["Fac"]
        if step:
            gt = nodes.new("ShaderNodeMath")
            gt.operation = 'GREATER_THAN'
            gt.inputs[1].default_value = 0.5
            links.new(height, gt.inputs[0])
            height = gt.outputs[0]
        links.new(height, disp.inputs["Height"])
        links.new(disp.outputs["Displacement"], nodes["Material Output"].inputs["Displacement"])
    if hasattr(mat, "displacement_method"):
        mat.displacement_method = method
    else:
        mat.cycles.displacement_method = method
    return mat


def render(scene, sphere, mat, engine, samples, name):
    sphere.data.materials.clear()
    sphere.data.materials.append(mat)
    return U.render_combined(scene, engine, samples, os.path.join(OUT, name), letters="RGB")


def main():
    checks = U.Checks("displacement_bump")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    sphere = U.sphere_in_front(scene, (0.05, 0.05, 0.05))
    U.aimed_light(scene, 'AREA', (1.5, -3.0, 1.5), 200.0, 1.0)

    flat_cycles, index = render(scene, sphere, material(), "CYCLES", 1024, "cycles_flat")
    flat_ours, _ = render(scene, sphere, material(), "DEFERRED_RENDER", 256, "ours_flat")
    mask = U.interior_mask(index, radius=1) & (index == 1)
    checks.check(mask.sum() > 1000, "the sphere covers the frame", str(int(mask.sum())))

    for space, scale, step in (("OBJECT", 0.08, False), ("WORLD", 0.12, False), ("OBJECT", 0.01, True)):
        label = space + (" step" if step else "")
        cycles, _ = render(scene, sphere, material(space, scale, step=step), "CYCLES", 1024, f"cycles_{label}")
        ours, _ = render(scene, sphere, material(space, scale, step=step), "DEFERRED_RENDER", 256, f"ours_{label}")
        messages = " ".join(m for _, m in U.last_messages())
        checks.check("Displacement" not in messages, f"{label}: no warning of the Displacement", messages[:200])
        ratio = float(ours[mask].sum() / cycles[mask].sum())
        checks.check(abs(ratio - 1.0) < 0.01, f"{label}: the bumped sphere's light is Cycles'", f"{ratio:.4f}")
        # The bump's own pattern: what it changes against the flat surface.
        d_cycles = (cycles - flat_cycles)[mask].ravel()
        d_ours = (ours - flat_ours)[mask].ravel()
        corr = float(np.corrcoef(d_cycles, d_ours)[0, 1])
        rel = float(np.sqrt(np.mean((d_ours - d_cycles) ** 2) / np.mean(d_cycles ** 2)))
        print(f"  {label}: bump's change rms {np.sqrt(np.mean(d_cycles ** 2)):.4f} (Cycles), "
              f"correlation {corr:.4f}, relative error {rel:.4f}")
        checks.check(np.sqrt(np.mean(d_cycles ** 2)) > 0.01, f"{label}: the bump changes Cycles' image")
        checks.check(corr > 0.95 and rel < 0.3, f"{label}: the bump's pattern is Cycles'",
                     f"correlation {corr:.4f}, relative error {rel:.4f}")

    # Displacement Only: Cycles moves the surface; not rendered here, said so.
    ours, _ = render(scene, sphere, material("OBJECT", 0.08, "DISPLACEMENT"), "DEFERRED_RENDER", 256, "ours_true")
    messages = " ".join(m for _, m in U.last_messages())
    checks.check("Displacement Only" in messages, "'Displacement Only' is warned", messages[:200])
    # (Flat: the node graph's program against the constant material's, which
    # differ by float rounding and sampling, not by a bump's 0.05.)
    rms = float(np.sqrt(np.mean((ours - flat_ours)[mask] ** 2)))
    checks.check(rms < 0.005, "'Displacement Only' leaves the normal flat", f"rms {rms:.2g}")
    checks.finish()


main()

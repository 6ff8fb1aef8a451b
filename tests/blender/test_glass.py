"""Glass at Cycles' Max Bounces 0: Principled Transmission and the Glass BSDF
against Cycles 3.4.

Cycles shows a closed glass object at Max Bounces 0 as its reflection only:
the refraction ray meets the object's own far side (a second bounce, cut),
and a light's sample through the refraction lobe is shadowed by that far
side. So a Principled BSDF of Transmission T keeps diffuse and sheen at
(1 - metallic)(1 - T), its specular lobe at 1 - T (1 - metallic), and adds a
glass reflection of weight T (1 - metallic) fresnel(N.I, IOR); a Glass BSDF
is that reflection alone. The engine folds this into its Principled
parameter set (export/material.py fold_transmission and _glass for constant
materials, shaders/nodes/node_shader_lib.glsl for node materials). Before,
Transmission was ignored (the glass sphere of base colour (0.8, 0.5, 0.3)
below rendered as that diffuse surface: 22x Cycles' light, 1.9x at
Transmission 0.5) and a Glass BSDF drew as a diffuse surface of its colour
(37x), a Refraction BSDF too (mean 1.03 where Cycles' is black). A
Refraction BSDF alone is black at Max Bounces 0.

A smooth 64-segment sphere seen from 6 m at 96x96, a grey world (0.2),
one 1 m area light at (1.5, -3, 1.5); ours at 256 samples against Cycles
at 1024, the sphere's interior pixels summed. Each material is rendered
through the constant path and through a node graph (its Roughness through
a Math node, which the constant path does not fold).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_glass.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("glass")
BASE = (0.8, 0.5, 0.3, 1.0)
# (label, shader, inputs, bound on |sum ours / Cycles - 1|). The bounds hold
# the fold's approximations: one Fresnel curve for the specular and glass
# reflections (L.H's Fresnel where Cycles' glass takes N.I's), and for the
# Glass BSDF a colour that goes to white towards grazing.
CASES = (
    ("Principled, Transmission 1, roughness 0.3", "principled", {"Transmission": 1.0, "Roughness": 0.3}, 0.03),
    ("Principled, Transmission 1, roughness 0", "principled", {"Transmission": 1.0, "Roughness": 0.0}, 0.03),
    ("Principled, Transmission 0.5, roughness 0.3", "principled", {"Transmission": 0.5, "Roughness": 0.3}, 0.01),
    ("Principled, Transmission 1, metallic 0.5", "principled",
     {"Transmission": 1.0, "Metallic": 0.5, "Roughness": 0.3}, 0.01),
    # Metallic 1: no glass closure at all (T' = 0), a metal.
    ("Principled, Transmission 1, metallic 1", "principled",
     {"Transmission": 1.0, "Metallic": 1.0, "Roughness": 0.3}, 0.01),
    ("Glass BSDF, roughness 0.2", "glass", {"Roughness": 0.2}, 0.03),
    # Black in Cycles (mean 6e-7 of stray samples): checked in absolute terms.
    ("Refraction BSDF, roughness 0.3", "refraction", {"Roughness": 0.3}, None),
)


def material(shader, inputs, graph):
    mat = bpy.data.materials.new(f"{shader}_{len(bpy.data.materials)}")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    if shader in ("glass", "refraction"):
        nodes.remove(bsdf)
        bsdf = nodes.new("ShaderNodeBsdfGlass" if shader == "glass" else "ShaderNodeBsdfRefraction")
        bsdf.distribution = 'GGX'
        bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        links.new(bsdf.outputs[0], nodes["Material Output"].inputs["Surface"])
    else:
        bsdf.distribution = 'GGX'
        bsdf.inputs["Base Color"].default_value = BASE
    for name, value in inputs.items():
        bsdf.inputs[name].default_value = value
    if graph:
        add = nodes.new("ShaderNodeMath")
        add.operation = 'ADD'
        add.inputs[0].default_value = inputs["Roughness"]
        add.inputs[1].default_value = 0.0
        links.new(add.outputs[0], bsdf.inputs["Roughness"])
    return mat


def render(scene, engine, samples, name):
    return U.render_combined(scene, engine, samples, os.path.join(OUT, name), letters="RGB")


def main():
    checks = U.Checks("glass")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    sphere = U.sphere_in_front(scene, (0.2, 0.2, 0.2))
    U.aimed_light(scene, 'AREA', (1.5, -3.0, 1.5), 200.0, 1.0)
    for k, (label, shader, inputs, bound) in enumerate(CASES):
        sphere.data.materials.clear()
        sphere.data.materials.append(material(shader, inputs, graph=False))
        cycles, index = render(scene, "CYCLES", 1024, f"cycles_{k}")
        mask = U.interior_mask(index, radius=1) & (index == 1)
        ratios = []
        for graph in (False, True):
            sphere.data.materials.clear()
            sphere.data.materials.append(material(shader, inputs, graph))
            path = "node graph" if graph else "constant"
            ours, _ = render(scene, "DEFERRED_RENDER", 256, f"ours_{k}_{'graph' if graph else 'constant'}")
            if bound is None:
                means = (float(ours[mask].mean()), float(cycles[mask].mean()))
                ratios.append(means[0])
                print(f"  {label} ({path}): mean ours {means[0]:.3g}, Cycles {means[1]:.3g}")
                checks.check(mask.sum() > 1000 and means[0] < 1e-4 and means[1] < 1e-4,
                             f"{label} ({path}): black, as Cycles", f"{means[0]:.3g} vs {means[1]:.3g}")
            else:
                ratio = float(ours[mask].sum() / cycles[mask].sum())
                ratios.append(ratio)
                print(f"  {label} ({path}): sum ours / Cycles {ratio:.4f}, Cycles' mean {cycles[mask].mean():.4f}")
                checks.check(mask.sum() > 1000 and abs(ratio - 1.0) < bound,
                             f"{label} ({path}): the sphere's light is Cycles'", f"{ratio:.4f}, bound {bound}")
            messages = " ".join(m for _, m in U.last_messages())
            checks.check("refracted through the surface is not rendered" in messages,
                         f"{label} ({path}): the missing refraction is warned")
        # One formula in two places (Python for constant materials, GLSL for graphs).
        checks.check(abs(ratios[0] - ratios[1]) < 1e-3, f"{label}: the constant path and the node graph agree",
                     f"{ratios[0]:.5f} vs {ratios[1]:.5f}")
    checks.finish()


main()

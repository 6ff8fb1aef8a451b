"""Light groups against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90 with three light groups: "key" (the sun),
"fill" (the point light) and "env" (the world), and Box as an emissive
object in the group "glow" (its side material emits). Cycles (256 samples,
the reference) and this engine (64 samples) render Combined and the four
Combined_<group> passes. Checks:
  * the four passes exist, RGB, as Cycles registers them;
  * in ours the groups add up to Combined (every source is in a group),
    to float precision, pixel by pixel;
  * each group's image mean is Cycles' within 2 % (each is a sum of
    per-sample light of one source, as Combined is);
  * a group no source names is black; a light in no group is in no pass.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_light_groups.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("light_groups")
GROUPS = ("key", "fill", "env", "glow")


def setup(scene):
    layer = U.comparison_setup(scene, samples=64)
    scene.cycles.samples = 256  # the reference
    scene.cycles.seed = 7
    for name in GROUPS + ("empty",):
        layer.lightgroups.add(name=name)
    bpy.data.objects["Sun"].lightgroup = "key"
    bpy.data.objects["Point"].lightgroup = "fill"
    scene.world.lightgroup = "env"
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.2, 0.25, 1.0)
    box = bpy.data.objects["Box"]
    box.lightgroup = "glow"
    side = bpy.data.materials["MatBoxSide"].node_tree.nodes["Principled BSDF"]
    side.inputs["Emission"].default_value = (1.0, 0.4, 0.1, 1.0)
    side.inputs["Emission Strength"].default_value = 3.0


def render(scene, engine, name):
    scene.render.engine = engine
    channels = U.read_exr(U.render_exr(os.path.join(OUT, name), scene))
    combined = U.exr_pass(channels, "ViewLayer", "Combined", "RGB").astype(np.float64)
    groups = {}
    for g in GROUPS + ("empty",):
        key = f"ViewLayer.Combined_{g}.R"
        if key in channels:
            groups[g] = U.exr_pass(channels, "ViewLayer", f"Combined_{g}", "RGB").astype(np.float64)
    return combined, groups


def main():
    checks = U.Checks("light_groups")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    setup(scene)
    c_comb, c_groups = render(scene, "CYCLES", "cycles")
    o_comb, o_groups = render(scene, "DEFERRED_RENDER", "ours")
    checks.check(sorted(o_groups) == sorted(c_groups) == sorted(GROUPS + ("empty",)),
                 "a Combined_<group> pass per light group, as Cycles'", f"{sorted(o_groups)}")
    total = sum(o_groups[g] for g in GROUPS)
    worst = float(np.abs(total - o_comb).max() / max(o_comb.max(), 1e-6))
    checks.check(worst < 1e-4, "the groups add up to Combined", f"{worst:.2e} of the peak")
    for g in GROUPS:
        c, o = c_groups[g].mean(), o_groups[g].mean()
        print(f"  {g}: Cycles {c:.5f}, ours {o:.5f}, ratio {o / c:.4f}")
        checks.check(c > 1e-3 and abs(o / c - 1.0) < 0.02, f"group '{g}': mean within 2 % of Cycles'",
                     f"ratio {o / c:.4f}")
    checks.check(float(np.abs(o_groups["empty"]).max()) == 0.0, "a group nothing names is black")

    # The point light in no group: its light is in Combined but in no pass.
    bpy.data.objects["Point"].lightgroup = ""
    o_comb2, o_groups2 = render(scene, "DEFERRED_RENDER", "ours_ungrouped")
    checks.check(float(np.abs(o_groups2["fill"]).max()) == 0.0, "a light in no group is in no group's pass")
    missing = float((o_comb2 - sum(o_groups2[g] for g in GROUPS)).mean())
    checks.check(abs(missing - o_groups["fill"].mean()) < 0.02 * o_groups["fill"].mean() + 1e-6,
                 "... and Combined minus the groups is its light", f"{missing:.5f} vs {o_groups['fill'].mean():.5f}")
    checks.finish()


main()

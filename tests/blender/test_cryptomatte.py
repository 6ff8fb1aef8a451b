"""Cryptomatte against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90 with the Object, Material and Asset layers on
(Levels 6) and a compositor of Render Layers -> Cryptomatte (source Render,
CryptoObject, matte "SphereB") -> Composite, rendered by Cycles and by this
engine at 32 samples into multilayer EXRs. Checks:
  * the same Crypto passes and channel names (CryptoObject00..02, rgba);
  * the same metadata keys and values: layer names, hash, conversion, and
    manifests (object and asset: equal; material: ours lists the scene's
    materials, each with Cycles' hash; Cycles adds its internal shaders);
  * per pixel, the rank-0 id equals Cycles' where Cycles' rank-0 coverage
    is above 0.9 (no edge), on at least 99.5 % of those pixels; where a
    pixel sees only geometry, the coverages add up to 1;
  * the compositor's Cryptomatte node picks SphereB from ours as from
    Cycles: intersection over union of the mattes (> 0.5) at least 0.98,
    mean |difference| below 0.01 (edges differ by sampling noise);
  * Levels 2 gives one pass per layer; no layer asked: no Crypto pass.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_cryptomatte.py
"""

import json
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("cryptomatte")
SAMPLES = 32


def setup(scene):
    layer = U.comparison_setup(scene, samples=SAMPLES)
    scene.cycles.seed = 5
    layer.use_pass_cryptomatte_object = True
    layer.use_pass_cryptomatte_material = True
    layer.use_pass_cryptomatte_asset = True
    layer.pass_cryptomatte_depth = 6
    scene.use_nodes = True
    tree = scene.node_tree
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    layers = tree.nodes.new("CompositorNodeRLayers")
    matte = tree.nodes.new("CompositorNodeCryptomatteV2")
    matte.source = 'RENDER'
    matte.scene = scene
    # The items are the scene's layers ("ViewLayer.CryptoObject", ...) once
    # the engine's passes are known, bare kinds before.
    try:
        matte.layer_name = "ViewLayer.CryptoObject"
    except TypeError:
        matte.layer_name = "CryptoObject"
    matte.matte_id = "SphereB"
    composite = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(layers.outputs["Image"], matte.inputs["Image"])
    tree.links.new(matte.outputs["Matte"], composite.inputs["Image"])
    scene.render.use_compositing = True


def render(scene, engine, name):
    """(channels dict, metadata dict) of a multilayer EXR render."""
    scene.render.engine = engine
    path = U.render_exr(os.path.join(OUT, name), scene)
    oiio = U._oiio()
    inp = oiio.ImageInput.open(path)
    meta = {a.name: a.value for a in inp.spec().extra_attribs if a.name.startswith("cryptomatte/")}
    inp.close()
    return U.read_exr(path), meta


def crypto_channels(channels):
    return sorted(k for k in channels if ".Crypto" in k)


def ids_and_coverage(channels, layer):
    """(ids uint32 (H, W, ranks), coverage (H, W, ranks)) of one layer."""
    ids, cov = [], []
    k = 0
    while f"ViewLayer.{layer}{k:02d}.r" in channels:
        for a, b in (("r", "g"), ("b", "a")):
            ids.append(np.ascontiguousarray(channels[f"ViewLayer.{layer}{k:02d}.{a}"], dtype=np.float32).view(np.uint32))
            cov.append(channels[f"ViewLayer.{layer}{k:02d}.{b}"].astype(np.float64))
        k += 1
    return np.stack(ids, axis=-1), np.stack(cov, axis=-1)


def main():
    checks = U.Checks("cryptomatte")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    setup(scene)
    cycles, cycles_meta = render(scene, "CYCLES", "cycles")
    ours, ours_meta = render(scene, "DEFERRED_RENDER", "ours")

    checks.check(crypto_channels(ours) == crypto_channels(cycles) and len(crypto_channels(ours)) == 36,
                 "the same Crypto passes and channels as Cycles", f"{len(crypto_channels(ours))} channels")
    checks.check(sorted(ours_meta) == sorted(cycles_meta), "the same metadata keys as Cycles",
                 f"{sorted(ours_meta)}")
    for key, value in sorted(cycles_meta.items()):
        mine = ours_meta.get(key)
        if key.endswith("/manifest"):
            theirs, ours_manifest = json.loads(value), json.loads(mine or "{}")
            if "CryptoMaterial" in cycles_meta.get(key.replace("/manifest", "/name"), ""):
                ok = bool(ours_manifest) and all(theirs.get(n) == h for n, h in ours_manifest.items())
                checks.check(ok, f"{key}: every material of ours with Cycles' hash", f"{ours_manifest}")
            else:
                checks.check(ours_manifest == theirs, f"{key}: the manifest is Cycles'", f"{ours_manifest}")
        else:
            checks.check(mine == value, f"{key} = {value!r}", f"{mine!r}")

    for layer in ("CryptoObject", "CryptoMaterial", "CryptoAsset"):
        c_ids, c_cov = ids_and_coverage(cycles, layer)
        o_ids, o_cov = ids_and_coverage(ours, layer)
        solid = c_cov[..., 0] > 0.9
        same = float((o_ids[..., 0][solid] == c_ids[..., 0][solid]).mean())
        print(f"  {layer}: rank-0 id equal to Cycles' on {same:.4f} of {int(solid.sum())} solid pixels")
        checks.check(solid.sum() > 5000 and same >= 0.995, f"{layer}: rank-0 ids are Cycles'", f"{same:.4f}")
        # Pixels whose every sample saw geometry: the coverages add up to 1.
        inside = c_cov.sum(axis=-1) > 0.999
        total = o_cov.sum(axis=-1)[inside]
        worst = float(np.abs(total - 1.0).max())
        checks.check(worst < 1e-4, f"{layer}: coverage adds up to 1 where only geometry is seen", f"{worst:.2e}")

    c_matte = cycles["Composite.Combined.R"].astype(np.float64)
    o_matte = ours["Composite.Combined.R"].astype(np.float64)
    union = (c_matte > 0.5) | (o_matte > 0.5)
    iou = float(((c_matte > 0.5) & (o_matte > 0.5)).sum() / max(union.sum(), 1))
    diff = float(np.abs(c_matte - o_matte).mean())
    print(f"  compositor Cryptomatte matte of SphereB: IoU {iou:.4f}, mean |difference| {diff:.2e}, "
          f"{int((o_matte > 0.5).sum())} px")
    checks.check(iou >= 0.98 and diff < 0.01 and (o_matte > 0.5).sum() > 500,
                 "the compositor's Cryptomatte node picks SphereB from ours as from Cycles",
                 f"IoU {iou:.4f}, mean diff {diff:.2e}")

    checks.run("Levels 2", levels_two, checks, scene)
    checks.run("no Cryptomatte", none_asked, checks, scene)
    checks.finish()


def levels_two(checks, scene):
    """Levels 2, where pixels on edges see more ids than slots: Cycles adds
    the extra coverage to the last slot (film_write_cryptomatte_slots), so
    coverage still adds up to 1; and its Accurate Mode changes nothing in
    3.4 (the unbounded per-pixel map is no longer built), nor in ours."""
    layer = scene.view_layers[0]
    layer.pass_cryptomatte_depth = 2
    scene.use_nodes = False
    try:
        channels, _ = render(scene, "DEFERRED_RENDER", "levels2")
        layer.use_pass_cryptomatte_accurate = True
        accurate, _ = render(scene, "DEFERRED_RENDER", "levels2_accurate")
        cycles_accurate, _ = render(scene, "CYCLES", "levels2_cycles_accurate")
        layer.use_pass_cryptomatte_accurate = False
        cycles, _ = render(scene, "CYCLES", "levels2_cycles")
    finally:
        layer.pass_cryptomatte_depth = 6
        layer.use_pass_cryptomatte_accurate = False
    names = crypto_channels(channels)
    checks.check(len(names) == 12 and all("00." in n for n in names), "Levels 2: one pass per layer", f"{names}")
    same = all(np.array_equal(cycles[n], cycles_accurate[n]) for n in crypto_channels(cycles))
    checks.check(same, "Cycles 3.4 renders the same with Accurate Mode on")
    same = all(np.array_equal(channels[n], accurate[n]) for n in names)
    checks.check(same, "ours too")
    for kind in ("CryptoObject", "CryptoMaterial", "CryptoAsset"):
        c_ids, c_cov = ids_and_coverage(cycles, kind)
        o_ids, o_cov = ids_and_coverage(channels, kind)
        inside = c_cov.sum(axis=-1) > 0.999  # pixels whose every sample saw geometry, some with 3 ids
        worst = float(np.abs(o_cov.sum(axis=-1)[inside] - 1.0).max())
        checks.check(inside.sum() > 5000 and worst < 1e-4,
                     f"Levels 2, {kind}: coverage adds up to 1 (extra ids in the last slot, as Cycles)",
                     f"{worst:.2e}")


def none_asked(checks, scene):
    layer = scene.view_layers[0]
    for flag in ("use_pass_cryptomatte_object", "use_pass_cryptomatte_material", "use_pass_cryptomatte_asset"):
        setattr(layer, flag, False)
    channels, meta = render(scene, "DEFERRED_RENDER", "none")
    checks.check(not crypto_channels(channels) and not meta, "no layer asked: no Crypto pass, no metadata",
                 f"{crypto_channels(channels)} {sorted(meta)}")


main()

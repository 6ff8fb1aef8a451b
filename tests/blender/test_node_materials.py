"""Node materials through real Blender: what the tree walk follows (groups,
reroutes, mutes), what it names in warnings, bad trees, the Emission pass,
and the program cache across renders. Per-node accuracy against Cycles is
test_node_probes.py's job."""

import math
import os
import time
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("node_materials")


def setup_scene():
    scene = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    bpy.ops.mesh.primitive_plane_add(size=2)
    plane = bpy.context.object
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.data.type = 'ORTHO'
    cam.data.ortho_scale = 2.0
    cam.location = (0, 0, 5)
    scene.world.use_nodes = False
    scene.world.color = (0, 0, 0)
    scene.render.resolution_x = scene.render.resolution_y = 16
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = 1
    return scene, plane


def empty_material(name):
    """A node material with only its Output node: (material, tree, output)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new("ShaderNodeOutputMaterial")


def emission_material(name):
    """A material whose Surface is an Emission shader; returns (material, emission node)."""
    mat, nt, out = empty_material(name)
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    return mat, em


def render_combined(scene, plane, mat, tag, passes=("Combined",)):
    plane.data.materials.clear()
    plane.data.materials.append(mat)
    from deferred_render.engine import final
    final.last_messages.clear()
    path = U.render_exr(os.path.join(OUT, tag), scene)
    channels = U.read_exr(path)
    return {p: U.exr_pass(channels, "ViewLayer", p, "RGB") for p in passes}, U.last_messages()


def warnings_of(messages):
    return [m for level, m in messages if level == "WARNING"]


def centre(img):
    return img[img.shape[0] // 2, img.shape[1] // 2]


def test_groups_reroutes_mutes(checks, scene, plane):
    # inner group: Value * 2; outer group: inner(group input) with the group
    # input left unlinked at 0.3 -> 0.6, through a reroute and a muted Add.
    inner = bpy.data.node_groups.new("Inner", "ShaderNodeTree")
    inner.inputs.new("NodeSocketFloat", "x")
    inner.outputs.new("NodeSocketFloat", "y")
    gi, go = inner.nodes.new("NodeGroupInput"), inner.nodes.new("NodeGroupOutput")
    mul = inner.nodes.new("ShaderNodeMath")
    mul.operation = 'MULTIPLY'
    mul.inputs[1].default_value = 2.0
    inner.links.new(gi.outputs[0], mul.inputs[0])
    inner.links.new(mul.outputs[0], go.inputs[0])
    outer = bpy.data.node_groups.new("Outer", "ShaderNodeTree")
    outer.inputs.new("NodeSocketFloat", "a")
    outer.outputs.new("NodeSocketFloat", "b")
    ogi, ogo = outer.nodes.new("NodeGroupInput"), outer.nodes.new("NodeGroupOutput")
    nested = outer.nodes.new("ShaderNodeGroup")
    nested.node_tree = inner
    outer.links.new(ogi.outputs[0], nested.inputs[0])
    outer.links.new(nested.outputs[0], ogo.inputs[0])

    mat, em = emission_material("groups")
    nt = mat.node_tree
    group = nt.nodes.new("ShaderNodeGroup")
    group.node_tree = outer
    group.inputs[0].default_value = 0.3
    reroute = nt.nodes.new("NodeReroute")
    add = nt.nodes.new("ShaderNodeMath")
    add.operation = 'ADD'
    add.inputs[1].default_value = 100.0
    add.mute = True
    nt.links.new(group.outputs[0], reroute.inputs[0])
    nt.links.new(reroute.outputs[0], add.inputs[0])
    nt.links.new(add.outputs[0], em.inputs["Color"])
    images, messages = render_combined(scene, plane, mat, "groups")
    value = centre(images["Combined"])
    checks.check(np.allclose(value, 0.6, atol=1e-6), "nested groups, reroute and muted Add give 0.3 x 2",
                 f"{value}")
    checks.check(not warnings_of(messages), "no warning", str(warnings_of(messages)))


def test_unsupported_node_named(checks, scene, plane):
    mat, em = emission_material("unsupported")
    node = mat.node_tree.nodes.new("ShaderNodeTexPointDensity")
    mat.node_tree.links.new(node.outputs["Color"], em.inputs["Color"])
    images, messages = render_combined(scene, plane, mat, "unsupported")
    w = warnings_of(messages)
    named = [m for m in w if "Point Density" in m and "'unsupported'" in m]
    checks.check(len(named) == 1, "an unsupported node is named in one warning of its material", str(w))
    checks.check(np.allclose(centre(images["Combined"]), 0.0), "its output takes the default (black)")


def _hash_uint(kx):
    """Cycles' hash_uint (util/hash.h: lookup3's final mix)."""
    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF
    a = b = c = (0xdeadbeef + (1 << 2) + 13) & 0xFFFFFFFF
    a = (a + kx) & 0xFFFFFFFF
    c = ((c ^ b) - rot(b, 14)) & 0xFFFFFFFF
    a = ((a ^ c) - rot(c, 11)) & 0xFFFFFFFF
    b = ((b ^ a) - rot(a, 25)) & 0xFFFFFFFF
    c = ((c ^ b) - rot(b, 16)) & 0xFFFFFFFF
    a = ((a ^ c) - rot(c, 4)) & 0xFFFFFFFF
    b = ((b ^ a) - rot(a, 14)) & 0xFFFFFFFF
    c = ((c ^ b) - rot(b, 24)) & 0xFFFFFFFF
    return c


def test_geometry_mesh_values(checks, scene, plane):
    """Geometry Pointiness and Random Per Island come from the export
    (native/src/mesh_attributes.cpp; against Cycles in test_node_probes):
    a flat plane's pointiness is 0.5 (every edge lies in the plane), its
    island value is Cycles' hash of its disjoint-set root (recomputed here
    from the plane's edges); an Auto Smooth mesh, which Cycles splits
    first, is named in a warning."""
    mat, em = emission_material("mesh_values")
    geometry = mat.node_tree.nodes.new("ShaderNodeNewGeometry")
    combine = mat.node_tree.nodes.new("ShaderNodeCombineXYZ")
    mat.node_tree.links.new(geometry.outputs["Pointiness"], combine.inputs["X"])
    mat.node_tree.links.new(geometry.outputs["Random Per Island"], combine.inputs["Y"])
    mat.node_tree.links.new(combine.outputs["Vector"], em.inputs["Color"])
    images, messages = render_combined(scene, plane, mat, "mesh_values")
    c = centre(images["Combined"])
    checks.check(abs(c[0] - 0.5) < 1e-6, "a flat plane's Pointiness is 0.5", f"{c[0]:.7f}")
    parent = list(range(len(plane.data.vertices)))
    rank = [0] * len(parent)

    def find(x):
        while parent[x] != x:
            x = parent[x]
        return x
    for e in plane.data.edges:   # util/disjoint_set.h: union by rank, in edge order
        x, y = find(e.vertices[0]), find(e.vertices[1])
        if x != y:
            if rank[x] < rank[y]:
                x, y = y, x
            parent[y] = x
            rank[x] += rank[x] == rank[y]
    expect = np.float32(_hash_uint(find(0))) / np.float32(4294967295.0)
    checks.check(c[1] == expect and not warnings_of(messages),
                 "Random Per Island is Cycles' hash of the plane's island root, without a warning",
                 f"{c[1]:.8f} vs {expect:.8f}, {warnings_of(messages)}")
    plane.data.use_auto_smooth = True
    try:
        _, messages = render_combined(scene, plane, mat, "mesh_values_auto_smooth")
    finally:
        plane.data.use_auto_smooth = False
    w = [m for m in warnings_of(messages) if "Auto Smooth" in m]
    checks.check(len(w) == 2, "on an Auto Smooth mesh both are named in warnings", str(warnings_of(messages)))


def test_alpha_rendered(checks, scene, plane):
    """Alpha is rendered (stochastic transparency; measured against Cycles
    by test_transparency.py): no warning, and the plane over the black world
    keeps 0.4 of its colour."""
    mat = bpy.data.materials.new("glass pane")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Alpha"].default_value = 0.4
    tex = mat.node_tree.nodes.new("ShaderNodeTexCoord")
    mat.node_tree.links.new(tex.outputs["Generated"], bsdf.inputs["Base Color"])
    bsdf.inputs["Emission"].default_value = (1.0, 1.0, 1.0, 1.0)  # emits: no light needed
    bsdf.inputs["Emission Strength"].default_value = 1.0
    images, messages = render_combined(scene, plane, mat, "alpha")
    w = warnings_of(messages)
    checks.check(not any("glass pane" in m for m in w), "alpha 0.4 is rendered, not warned about", str(w))
    bsdf.inputs["Alpha"].default_value = 1.0
    opaque, _ = render_combined(scene, plane, mat, "alpha_opaque")
    ratio = float(images["Combined"].mean() / max(opaque["Combined"].mean(), 1e-9))
    checks.check(abs(ratio - 0.4) < 0.05, "the pane keeps about 0.4 of its light", f"{ratio:.3f}")


def test_bad_trees(checks, scene, plane):
    # A link cycle (Blender marks one link invalid), a group without an
    # output, NaN in a Value node: a sane image and no crash.
    mat, em = emission_material("bad trees")
    nt = mat.node_tree
    a, b = nt.nodes.new("ShaderNodeMath"), nt.nodes.new("ShaderNodeMath")
    nt.links.new(a.outputs[0], b.inputs[0])
    nt.links.new(b.outputs[0], a.inputs[0])
    empty = bpy.data.node_groups.new("NoOutput", "ShaderNodeTree")
    empty.outputs.new("NodeSocketFloat", "v")
    group = nt.nodes.new("ShaderNodeGroup")
    group.node_tree = empty
    value = nt.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = float("nan")
    add = nt.nodes.new("ShaderNodeMath")
    nt.links.new(b.outputs[0], add.inputs[0])
    nt.links.new(group.outputs[0], add.inputs[1])
    add2 = nt.nodes.new("ShaderNodeMath")
    nt.links.new(add.outputs[0], add2.inputs[0])
    nt.links.new(value.outputs[0], add2.inputs[1])
    nt.links.new(add2.outputs[0], em.inputs["Strength"])
    images, messages = render_combined(scene, plane, mat, "bad_trees")
    img = images["Combined"]
    checks.check(np.isfinite(img).all(), "the image is finite")
    errors = [m for level, m in messages if level == "ERROR"]
    checks.check(not errors, "no error", str(errors))


def test_image_sizes(checks, scene, plane):
    """A 1x1 image is its texel everywhere; an image 16384 px wide is scaled
    to 8192 with a warning, and renders."""
    def image_material(name, image):
        mat, em = emission_material(name)
        tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = image
        tex.interpolation = 'Closest'
        mat.node_tree.links.new(tex.outputs["Color"], em.inputs["Color"])
        return mat

    tiny = bpy.data.images.new("tiny", 1, 1)
    tiny.colorspace_settings.name = 'Non-Color'  # first: changing it regenerates the pixels
    tiny.pixels.foreach_set(np.array([0.5, 0.25, 1.0, 1.0], dtype=np.float32))
    images, messages = render_combined(scene, plane, image_material("tiny image", tiny), "tiny_image")
    img = images["Combined"]
    want = np.round(np.array([0.5, 0.25, 1.0]) * 255) / 255  # 8-bit texel, Non-Color
    checks.check(np.abs(img - want).max() < 1e-6, "a 1x1 image fills the surface with its texel",
                 f"{centre(img)} vs {want}")

    wide = bpy.data.images.new("wide", 16384, 16)
    wide.generated_type = 'COLOR_GRID'
    images, messages = render_combined(scene, plane, image_material("wide image", wide), "wide_image")
    w = warnings_of(messages)
    checks.check(any("16384x16" in m and "8192" in m for m in w), "a 16384 px image is scaled to 8192, warned",
                 str(w))
    checks.check(np.isfinite(images["Combined"]).all() and images["Combined"].max() > 0.0,
                 "and it renders")


def test_emission_pass(checks, scene, plane):
    scene.view_layers[0].use_pass_emit = True
    mat, em = emission_material("textured emission")
    tex = mat.node_tree.nodes.new("ShaderNodeTexCoord")
    mat.node_tree.links.new(tex.outputs["Generated"], em.inputs["Color"])
    images, _ = render_combined(scene, plane, mat, "emit", passes=("Combined", "Emit"))
    combined, emit = images["Combined"], images["Emit"]
    checks.check(np.abs(combined - emit).max() < 1e-6 and emit.max() > 0.9,
                 "textured emission fills the Emission pass as it does Combined",
                 f"max |diff| {np.abs(combined - emit).max():.2e}")
    # Generated = (P + 1) / 2 on the 2 m plane: the pixel centres' values.
    n = emit.shape[1]
    want = (np.arange(n) + 0.5) / n
    checks.check(np.abs(emit[n // 2, :, 0] - want).max() < 1e-5, "generated x across the image",
                 f"{np.abs(emit[n // 2, :, 0] - want).max():.2e}")
    scene.view_layers[0].use_pass_emit = False


def test_program_cache(checks, scene, plane):
    # The disk cache between renderers: each render here starts a new one
    # (a render keeps its renderer's programs for the next, session.py).
    from deferred_render.engine import final, session
    os.environ["DEFERRED_SHADER_CACHE"] = tempfile.mkdtemp(prefix="deferred_programs_")
    mat, em = emission_material("cached")
    math_node = mat.node_tree.nodes.new("ShaderNodeMath")
    mat.node_tree.links.new(math_node.outputs[0], em.inputs["Strength"])
    session.release()
    render_combined(scene, plane, mat, "cache_cold")
    cold = dict(final.last_timings)
    math_node.inputs[0].default_value = 0.75  # a value edit: same program
    session.release()
    images, _ = render_combined(scene, plane, mat, "cache_warm")
    warm = dict(final.last_timings)
    del os.environ["DEFERRED_SHADER_CACHE"]
    print(f"  cold: {cold.get('programs_compiled')} compiled ({cold.get('compile_ms', 0):.0f} ms); "
          f"warm: {warm.get('programs_compiled')} compiled, {warm.get('programs_loaded')} loaded "
          f"({warm.get('load_ms', 0):.0f} ms)")
    checks.check(cold.get("programs_compiled", 0) > 0, "the first render compiles its programs")
    if warm.get("programs_loaded", 0) == 0 and warm.get("programs_compiled", 0) > 0:
        print("  skip: the driver keeps no program binaries (no disk cache here)")
        return
    checks.check(warm.get("programs_compiled", -1) == 0, "the second render of the file compiles nothing",
                 str(warm))
    checks.check(np.allclose(centre(images["Combined"]), 0.75 + 0.5, atol=1e-5),
                 "the edited value is rendered (Math Add 0.75 + 0.5)", f"{centre(images['Combined'])}")


def test_persistent_data(checks, scene, plane):
    """Render Properties > Persistent Data keeps the native renderer between
    renders: the second render of an unchanged scene compiles nothing (the
    disk cache is off, so this is the kept programs) and uploads no image
    (found by its content key); a changed image is uploaded again; turning
    the option off releases the kept renderer's data and keeps its context
    and programs (the next render links nothing and uploads its image)."""
    from deferred_render.engine import final, session
    os.environ["DEFERRED_SHADER_CACHE"] = "off"
    try:
        image = bpy.data.images.new("persistent grid", 64, 32)
        image.generated_type = 'COLOR_GRID'
        mat, em = emission_material("persistent image")
        tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = image
        mat.node_tree.links.new(tex.outputs["Color"], em.inputs["Color"])
        scene.render.use_persistent_data = True
        session.release()
        runs = []
        for tag in ("persistent_1", "persistent_2"):
            t0 = time.perf_counter()
            images, _ = render_combined(scene, plane, mat, tag)
            runs.append((images["Combined"], dict(final.last_timings), time.perf_counter() - t0))
        (first, t1, s1), (second, t2, s2) = runs
        print(f"  first render {s1:.2f} s ({t1.get('programs_compiled')} programs compiled, "
              f"{t1.get('images_uploaded')} images uploaded); second {s2:.2f} s "
              f"({t2.get('programs_compiled')} compiled, {t2.get('programs_loaded')} loaded, "
              f"{t2.get('images_uploaded')} uploaded, {t2.get('images_reused')} reused)")
        checks.check(session.kept(), "the renderer is kept after a render with Persistent Data")
        checks.check(t1.get("programs_compiled", 0) > 0 and t1.get("images_uploaded") == 1,
                     "the first render compiles and uploads the image", str(t1))
        checks.check(t2.get("programs_compiled") == 0 and t2.get("programs_loaded") == 0,
                     "the second render compiles nothing and loads nothing (programs kept)", str(t2))
        checks.check(t2.get("images_uploaded") == 0 and t2.get("images_reused") == 1,
                     "the second render uploads no image (found by its key)", str(t2))
        checks.check(np.array_equal(first, second) and first.max() > 0.1, "and renders the same image",
                     f"max |diff| {np.abs(first - second).max():.2e}")

        image.generated_type = 'UV_GRID'  # new content: a new key
        images, _ = render_combined(scene, plane, mat, "persistent_3")
        t3 = dict(final.last_timings)
        checks.check(t3.get("images_uploaded") == 1 and t3.get("images_reused") == 0,
                     "a changed image is uploaded again", str(t3))
        checks.check(np.abs(images["Combined"] - second).max() > 0.1, "and the new content is rendered")

        # Off: the data goes (the kept renderer releases it at the render's
        # start and at its end), the context and its programs stay.
        scene.render.use_persistent_data = False
        off = []
        for tag in ("persistent_off_1", "persistent_off_2"):
            images, _ = render_combined(scene, plane, mat, tag)
            off.append((images["Combined"], dict(final.last_timings)))
            checks.check(not session.kept() and session.renderers_held() == 1,
                         f"with the option off ({tag}), no data is kept after the render, only the renderer",
                         f"kept {session.kept()}, held {session.renderers_held()}")
        for (pixels, t), tag in zip(off, ("first", "second")):
            checks.check(t.get("images_uploaded") == 1 and t.get("images_reused") == 0,
                         f"the {tag} render with the option off uploads its image again", str(t))
            checks.check(t.get("programs_compiled") == 0 and t.get("programs_loaded") == 0,
                         "and compiles and loads no program (the context's are kept)", str(t))
            checks.check(np.array_equal(pixels, images["Combined"]) and
                         np.array_equal(off[0][0], off[1][0]) and pixels.max() > 0.1,
                         "and renders the same image", f"max {pixels.max():.3f}")
        # A renderer that starts afresh renders it the same.
        session.release()
        fresh, _ = render_combined(scene, plane, mat, "persistent_off_fresh")
        checks.check(final.last_timings.get("programs_compiled", 0) > 0 and
                     np.array_equal(fresh["Combined"], off[1][0]),
                     "a new renderer (programs compiled again) renders the same image",
                     f"max |diff| {np.abs(fresh['Combined'] - off[1][0]).max():.2e}")
    finally:
        scene.render.use_persistent_data = False
        session.release()
        del os.environ["DEFERRED_SHADER_CACHE"]


def test_diffuse_glossy_summed(checks, scene, plane):
    """A Mix (or Add) of a Lambert Diffuse BSDF and a grey Glossy BSDF is
    one closure, their sum as Cycles evaluates it, in every sample: at 1
    sample each pixel equals the Diffuse at its weight plus the Glossy at
    its weight, rendered apart (one of the two drawn per sample, as before,
    leaves each pixel at one of them whole: the speckles of a sharp glossy
    highlight in a few of a pixel's samples) — constant sets (the
    exporter's) and node graphs (a Fresnel factor or colour: the graph's
    program) alike, mixed again with an Emission too. DiffCol / GlossCol
    carry the two weights. A tinted Glossy is still drawn one side at a
    time: right in the mean only."""
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", 'SUN'))
    scene.collection.objects.link(sun)
    sun.data.energy = 3.0
    sun.data.angle = 0.0
    sun.rotation_euler = (math.radians(35), 0.0, math.radians(20))
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_color = layer.use_pass_glossy_color = True
    fac, cd, k, rough = 0.3, (0.8, 0.5, 0.2), 0.9, 0.4
    f0 = ((4.0 - 1.0) / (4.0 + 1.0)) ** 2  # a Fresnel node of IOR 4 seen head on: fresnel_dielectric_cos(1, 4)

    def bsdfs(nt, diffuse_color, glossy_color):
        diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*diffuse_color, 1.0)
        glossy = nt.nodes.new("ShaderNodeBsdfGlossy")
        glossy.distribution = 'BECKMANN'
        glossy.inputs["Color"].default_value = (*glossy_color, 1.0)
        glossy.inputs["Roughness"].default_value = rough
        return diffuse, glossy

    def fresnel(nt):
        node = nt.nodes.new("ShaderNodeFresnel")
        node.inputs["IOR"].default_value = 4.0
        return node.outputs[0]

    def alone(name, which, color):
        mat, nt, out = empty_material(name)
        diffuse, glossy = bsdfs(nt, color, color)
        nt.links.new((diffuse if which == "diffuse" else glossy).outputs[0], out.inputs["Surface"])
        return mat

    def mixed(name, glossy_color=(k, k, k), mix_fac=fac, graph=False, emission=None):
        mat, nt, out = empty_material(name)
        diffuse, glossy = bsdfs(nt, cd, glossy_color)
        mix = nt.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = mix_fac
        if graph:
            nt.links.new(fresnel(nt), mix.inputs["Fac"])
        nt.links.new(diffuse.outputs[0], mix.inputs[1])
        nt.links.new(glossy.outputs[0], mix.inputs[2])
        surface = mix.outputs[0]
        if emission is not None:  # mixed again, half and half, with an Emission
            em = nt.nodes.new("ShaderNodeEmission")
            em.inputs["Color"].default_value = (*emission, 1.0)
            outer = nt.nodes.new("ShaderNodeMixShader")
            outer.inputs["Fac"].default_value = 0.5
            nt.links.new(surface, outer.inputs[1])
            nt.links.new(em.outputs[0], outer.inputs[2])
            surface = outer.outputs[0]
        nt.links.new(surface, out.inputs["Surface"])
        return mat

    def added(name, graph=False):
        mat, nt, out = empty_material(name)
        diffuse, glossy = bsdfs(nt, [c * (1 - fac) for c in cd], (k * fac,) * 3)
        if graph:
            nt.links.new(fresnel(nt), glossy.inputs["Color"])
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(glossy.outputs[0], add.inputs[0])
        nt.links.new(diffuse.outputs[0], add.inputs[1])
        nt.links.new(add.outputs[0], out.inputs["Surface"])
        return mat

    def render(mat):
        return render_combined(scene, plane, mat, mat.name, ("Combined", "DiffCol", "GlossCol"))[0]

    try:
        d = render(alone("dg_diffuse", "diffuse", [c * (1 - fac) for c in cd]))
        g = render(alone("dg_glossy", "glossy", (k * fac,) * 3))
        checks.check(float(g["Combined"].mean()) > 0.05 * float(d["Combined"].mean()),
                     "the glossy lobe lights the plane", f"glossy {g['Combined'].mean():.4g}")
        d0 = render(alone("dg_diffuse_f0", "diffuse", [c * (1 - f0) for c in cd]))
        g0 = render(alone("dg_glossy_f0", "glossy", (k * f0,) * 3))
        gf = render(alone("dg_glossy_fresnel", "glossy", (f0,) * 3))
        e = (0.2, 0.2, 0.2)
        cases = [
            ("mix", mixed("dg_mix"), d["Combined"] + g["Combined"], (1 - fac) * np.array(cd), k * fac),
            ("add", added("dg_add"), d["Combined"] + g["Combined"], (1 - fac) * np.array(cd), k * fac),
            ("node graph mix (Fresnel factor)", mixed("dg_graph_mix", graph=True),
             d0["Combined"] + g0["Combined"], (1 - f0) * np.array(cd), k * f0),
            ("node graph add (Fresnel colour)", added("dg_graph_add", graph=True),
             d["Combined"] + gf["Combined"], (1 - fac) * np.array(cd), f0),
            ("mix, mixed again with an Emission", mixed("dg_mix_emission", emission=e),
             0.5 * (d["Combined"] + g["Combined"]) + 0.5 * np.array(e), 0.5 * (1 - fac) * np.array(cd),
             0.5 * k * fac),
        ]
        for what, mat, expected, diffcol, glosscol in cases:
            r = render(mat)
            err = float(np.abs(r["Combined"] - expected).max() / expected.max())
            checks.check(err < 2e-3, f"{what}: every pixel of 1 sample is the sum of its two BSDFs",
                         f"max |difference| / max {err:.3g}")
            dc = float(np.abs(r["DiffCol"] - diffcol).max())
            gc = float(np.abs(r["GlossCol"] - glosscol).max())
            checks.check(dc < 2e-3 and gc < 2e-3, f"{what}: DiffCol and GlossCol are the weighted colours",
                         f"DiffCol {dc:.3g}, GlossCol {gc:.3g} off")
        # A tinted glossy side cannot share the closure: drawn one at a time
        # (at 1 sample each pixel is one side whole), converging to the sum.
        tint = (0.9, 0.6, 0.3)
        r = render(mixed("dg_tint", glossy_color=tint))
        spread = float(r["Combined"][..., 0].std())
        checks.check(spread > 1e-3, "a tinted glossy side is still drawn one side at a time",
                     f"pixel spread {spread:.3g}")
        scene.deferred_render.samples = 64
        r = render(mixed("dg_tint_64", glossy_color=tint))
        scene.deferred_render.samples = 1
        g_t = render(alone("dg_tint_glossy", "glossy", [c * fac for c in tint]))
        inner = (slice(3, -3), slice(3, -3))  # the plane's edge pixels: background in the filter's reach
        want = float((d["Combined"] + g_t["Combined"])[inner].mean())
        rel = abs(float(r["Combined"][inner].mean()) - want) / want
        checks.check(rel < 0.02, "and its mean converges to the sum (64 samples)", f"relative difference {rel:.3g}")
    finally:
        scene.deferred_render.samples = 1
        layer.use_pass_diffuse_color = layer.use_pass_glossy_color = False
        bpy.data.objects.remove(sun)


def main():
    checks = U.Checks("node materials")
    if not U.require_engine(checks):
        checks.finish()
    scene, plane = setup_scene()
    for test in (test_groups_reroutes_mutes, test_unsupported_node_named, test_geometry_mesh_values,
                 test_alpha_rendered, test_bad_trees,
                 test_image_sizes, test_emission_pass, test_program_cache, test_persistent_data,
                 test_diffuse_glossy_summed):
        checks.run(test.__name__, test, checks, scene, plane)
    checks.finish()


main()

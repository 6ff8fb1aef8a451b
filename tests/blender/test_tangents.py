"""Tangents through the real export path against Blender's own MikkTSpace.

The add-on computes MikkTSpace natively over the loop triangles (as Cycles
3.4 does) instead of calling Mesh.calc_tangents. Blender's calc_tangents
runs the same algorithm (the C++ port in intern/mikktspace) over polygons,
so on meshes made of triangles the two must agree to rounding: Blender
sums a group's corners on threads above 10 000 faces, so the order of
additions may differ there, nowhere else (bound 1e-6; measured 0 on every
mesh below, 1.8e-7 on a 512 x 512 sphere). The meshes are smooth or Auto
Smooth: a flat triangle's corners read Cycles' triangle normal, not
Blender's polygon normal, so flat meshes are compared with Cycles instead
(test_node_probes). Also: an n-gon mesh gets tangents (calc_tangents
refuses n-gons), without a warning, and bad arrays are ValueErrors (which
the export turns into a warning naming the mesh).
Cycles itself is the reference in test_node_probes (normal maps and the
Tangent node on spheres and on a flat 12-gon).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_tangents.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render.export import mesh as mesh_export  # noqa: E402

BOUND = 1e-6


def clear():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)


def smart_uvs(ob):
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.uv.smart_project()
    bpy.ops.object.mode_set(mode='OBJECT')


def triangulated(ob):
    """The object with its faces triangulated (so its polygons are its loop triangles)."""
    ob.modifiers.new("triangulate", 'TRIANGULATE')
    return ob


def blender_tangents(ob):
    """Mesh.calc_tangents of the evaluated mesh, per loop triangle corner, and the triangle count."""
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    me = ev.to_mesh()
    try:
        me.calc_normals_split()
        me.calc_tangents(uvmap=me.uv_layers.active.name)
        n = len(me.loops)
        tangent = np.empty(n * 3, np.float32)
        me.loops.foreach_get("tangent", tangent)
        sign = np.empty(n, np.float32)
        me.loops.foreach_get("bitangent_sign", sign)
        me.calc_loop_triangles()
        loops = np.empty(len(me.loop_triangles) * 3, np.uint32)
        me.loop_triangles.foreach_get("loops", loops)
        return np.concatenate([tangent.reshape(n, 3)[loops], sign[loops, None]], axis=1)
    finally:
        ev.to_mesh_clear()


def exported_tangents(ob, warnings):
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    arrays = mesh_export.object_mesh_arrays(ev, ("tangent:",), warn=warnings.append)
    return dict(arrays.attributes).get("tangent:")


def compare(checks, name, ob):
    """Smooth (or auto smooth) meshes: calc_tangents reads the same normals as the export."""
    warnings = []
    ours = exported_tangents(ob, warnings)
    ref = blender_tangents(ob)
    if not checks.check(ours is not None and ours.shape == ref.shape and not warnings,
                        f"{name}: tangents exported", f"{warnings}"):
        return
    diff = np.abs(ours[:, :3] - ref[:, :3]).max()
    signs = int((ours[:, 3] != ref[:, 3]).sum())
    checks.check(diff <= BOUND and signs == 0, f"{name}: equal to Mesh.calc_tangents ({len(ref) // 3} triangles)",
                 f"max |diff| {diff:.2e}, {signs} bitangent signs differ")


def test_meshes(checks):
    clear()
    bpy.ops.mesh.primitive_monkey_add()
    bpy.ops.object.shade_smooth()
    smart_uvs(bpy.context.object)
    compare(checks, "Suzanne, smart UV project", triangulated(bpy.context.object))

    clear()
    bpy.ops.mesh.primitive_monkey_add()
    bpy.ops.object.shade_smooth()
    ob = bpy.context.object
    smart_uvs(ob)
    uv = ob.data.uv_layers.active.data
    co = np.array([ob.data.vertices[loop.vertex_index].co.x for loop in ob.data.loops])
    uvs = np.empty(len(uv) * 2, np.float32)
    uv.foreach_get("uv", uvs)
    uvs = uvs.reshape(-1, 2)
    uvs[co < 0, 0] *= -1.0   # the left half mirrored: its bitangent sign flips
    uv.foreach_set("uv", uvs.ravel())
    compare(checks, "Suzanne, left half's UVs mirrored", triangulated(ob))

    clear()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12)
    bpy.ops.object.shade_smooth()
    compare(checks, "UV sphere (seam, poles)", triangulated(bpy.context.object))

    clear()
    bpy.ops.mesh.primitive_cylinder_add(vertices=24)
    ob = bpy.context.object
    bpy.ops.object.shade_smooth()
    ob.data.use_auto_smooth = True   # split normals at the caps' rims
    smart_uvs(ob)
    compare(checks, "auto-smooth cylinder (split normals)", triangulated(ob))

    clear()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=12, y_subdivisions=12)
    ob = bpy.context.object
    bpy.ops.object.shade_smooth()
    verts = ob.data.vertices
    for i in range(0, len(verts) - 1, 9):   # slivers: two corners at one position
        verts[i].co = verts[i + 1].co
    uv = ob.data.uv_layers.active.data
    for i in range(0, len(uv), 7):          # triangles without UV area
        uv[i].uv = (0.5, 0.5)
    compare(checks, "grid with degenerate triangles and collapsed UVs", triangulated(ob))


def test_random_mesh(checks):
    """A mesh made to exercise every rule: random vertex displacement, UV
    islands cut at random faces (seams), mirrored islands (both bitangent
    signs around one vertex), collapsed UVs and sharp edges under auto
    smooth (split normals), triangulated so calc_tangents sees the same faces."""
    clear()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=40, ring_count=20)
    ob = bpy.context.object
    bpy.ops.object.shade_smooth()
    me = ob.data
    rng = np.random.default_rng(7)
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    me.vertices.foreach_set("co", co + rng.normal(0.0, 0.02, co.size).astype(np.float32))
    uv = me.uv_layers.active.data
    uvs = np.empty(len(uv) * 2, np.float32)
    uv.foreach_get("uv", uvs)
    uvs = uvs.reshape(-1, 2)
    for poly in me.polygons:
        loops = list(poly.loop_indices)
        roll = rng.random()
        if roll < 0.15:        # an island of its own, mirrored in u
            uvs[loops, 0] = 2.0 - uvs[loops, 0]
        elif roll < 0.25:      # an island shifted away (a seam all round)
            uvs[loops] += rng.random(2).astype(np.float32)
        elif roll < 0.30:      # no UV area
            uvs[loops] = uvs[loops[0]]
    uv.foreach_set("uv", uvs.ravel())
    me.use_auto_smooth = True
    me.auto_smooth_angle = 0.6
    sharp = rng.random(len(me.edges)) < 0.1
    me.edges.foreach_set("use_edge_sharp", sharp)
    compare(checks, "random sphere: displaced, islands, mirrors, no-area UVs, sharp edges", triangulated(ob))


def test_ngon(checks):
    """A cylinder's caps are n-gons: calc_tangents refuses them, the export does not."""
    clear()
    bpy.ops.mesh.primitive_cylinder_add(vertices=16)
    ob = bpy.context.object
    try:
        blender_tangents(ob)
        refused = False
    except RuntimeError:
        refused = True
    checks.check(refused, "Mesh.calc_tangents refuses the n-gon cylinder (why the export does not use it)")
    warnings = []
    ours = exported_tangents(ob, warnings)
    checks.check(ours is not None and not warnings, "its tangents are exported without a warning", f"{warnings}")
    if ours is None:
        return
    length = np.linalg.norm(ours[:, :3], axis=1)
    checks.check(np.abs(length - 1).max() < 1e-5 and np.isin(ours[:, 3], (-1.0, 1.0)).all(),
                 "unit tangents, bitangent signs of +-1", f"length {length.min():.6f}..{length.max():.6f}")
    # The caps lie in z = +-1 planes: their tangents lie in the plane too.
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    arrays = mesh_export.object_mesh_arrays(ev, ())
    caps = np.abs(np.abs(arrays.corner_normals[:, 2]) - 1) < 1e-6
    checks.check(caps.sum() > 0 and np.abs(ours[caps, 2]).max() < 1e-6, "the caps' tangents lie in the caps",
                 f"{int(caps.sum())} corners, max |z| {np.abs(ours[caps, 2]).max():.2e}")


def test_bad_input(checks):
    from deferred_render import native
    mod = native.load()
    p = np.zeros((3, 3), np.float32)
    i = np.array([[0, 1, 5]], np.uint32)
    n = np.tile(np.float32([0, 0, 1]), (3, 1))
    uv = np.zeros((3, 2), np.float32)
    for what, call in (("an index out of range", lambda: mod.compute_tangents(p, i, n, uv)),
                       ("too few corner normals", lambda: mod.compute_tangents(p, i[:, :3] * 0, n[:2], uv)),
                       ("float64 positions", lambda: mod.compute_tangents(p.astype(np.float64), i * 0, n, uv))):
        try:
            call()
            checks.check(False, f"{what}: ValueError")
        except ValueError as ex:
            checks.check(True, f"{what}: ValueError", str(ex)[:90])
    empty = mod.compute_tangents(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32),
                                 np.zeros((0, 3), np.float32), np.zeros((0, 2), np.float32))
    checks.check(empty.shape == (0, 4), "no triangles: an empty (0, 4) array")


def main():
    checks = U.Checks("tangents")
    if U.native_module() is None:
        checks.check(False, "the native module loads")
        checks.finish()
    for test in (test_meshes, test_random_mesh, test_ngon, test_bad_input):
        checks.run(test.__name__, test, checks)
    checks.finish()


main()

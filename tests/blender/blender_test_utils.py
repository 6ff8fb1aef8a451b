"""Helpers shared by the Blender test scripts (imported inside Blender).

Each test script runs as

    BLENDER_USER_SCRIPTS=<build>/blender_scripts DEFERRED_TEST_OUT=<dir> \
    blender -b --factory-startup <file.blend> --addons deferred_render -E DEFERRED_RENDER \
            --python-exit-code 1 --python tests/blender/test_X.py

(see run_blender_test.py and tests.cmake). Checks are collected by ``Checks``;
the script ends with ``checks.finish()`` which prints "N passed, N failed"
and exits non-zero if anything failed.

EXR files are read with OpenImageIO's Python module (Debian package
python3-openimageio, importable from Blender's Python 3.11): Blender 3.4's
``bpy.data.images.load`` gives no pixels for multilayer EXRs.
"""

import os
import subprocess
import sys
import tempfile
import time
import traceback

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
SAMPLES = os.path.join(REPO, "blend_samples")
ENGINE = "DEFERRED_RENDER"

# chan_id of each pass -> EXR channel suffixes (Blender writes ViewLayer.<Pass>.<letter>).
CHANNEL_LETTERS = {"RGBA": "RGBA", "RGB": "RGB", "Z": "Z", "XYZ": "XYZ", "UVA": "UVA", "X": "X", "XYZW": "XYZW"}


# ---------------------------------------------------------------------------
# checks
# ---------------------------------------------------------------------------

class Checks:
    def __init__(self, name):
        self.name = name
        self.passed = 0
        self.failed = []
        self.t0 = time.perf_counter()
        print(f"=== {name}")

    def check(self, condition, what, detail=""):
        if condition:
            self.passed += 1
            print(f"  ok    {what}" + (f"  [{detail}]" if detail else ""))
        else:
            self.failed.append(what)
            print(f"  FAIL  {what}" + (f"  [{detail}]" if detail else ""))
        return bool(condition)

    def run(self, what, func, *args, **kwargs):
        """Run a sub-test; an exception counts as one failure."""
        try:
            return func(*args, **kwargs)
        except Exception:
            traceback.print_exc()
            self.check(False, f"{what} raised")
            return None

    def finish(self):
        dt = time.perf_counter() - self.t0
        print(f"=== {self.name}: {dt:.1f} s")
        for what in self.failed:
            print(f"  failed: {what}")
        print(f"{self.passed} passed, {len(self.failed)} failed")
        sys.stdout.flush()
        if self.failed:
            sys.exit(1)


# ---------------------------------------------------------------------------
# environment
# ---------------------------------------------------------------------------

def out_dir(test_name):
    base = os.environ.get("DEFERRED_TEST_OUT") or os.path.join(tempfile.gettempdir(), "deferred_test_out")
    path = os.path.join(base, test_name)
    os.makedirs(path, exist_ok=True)
    return path


def native_module():
    """The add-on's deferred_native module, or None (with the reason printed)."""
    import deferred_render.native as native
    mod = native.try_load()
    if mod is None:
        print(f"  native module unavailable: {native.error_message()}")
    return mod


def require_engine(checks):
    engine = bpy.context.scene.render.engine
    checks.check(engine == ENGINE, f"scene render engine is {ENGINE}", engine)
    return engine == ENGINE


def last_messages():
    """(level, message) reported by the engine during the last render."""
    from deferred_render.engine import final
    return list(final.last_messages)


def blender_command(blend, *args, addons=True, engine=True):
    """The command line of a Blender subprocess rendering ``blend``.

    --addons comes before the file: a .blend saved with the Deferred engine
    then loads without "Engine 'DEFERRED_RENDER' not available"."""
    cmd = [bpy.app.binary_path, "-b", "--factory-startup"]
    if addons:
        cmd += ["--addons", "deferred_render"]
    cmd.append(blend)
    if engine:
        cmd += ["-E", ENGINE]
    return cmd + list(args)


def run_blender(cmd, timeout=600):
    """Run a Blender subprocess (same BLENDER_USER_SCRIPTS); returns (code, output)."""
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout,
                          env=dict(os.environ))
    return proc.returncode, proc.stdout.decode("utf-8", "replace")


# ---------------------------------------------------------------------------
# rendering and EXR reading
# ---------------------------------------------------------------------------

def set_all_passes(view_layer, on=True):
    for flag in ("use_pass_z", "use_pass_mist", "use_pass_position", "use_pass_normal", "use_pass_uv",
                 "use_pass_object_index", "use_pass_material_index", "use_pass_diffuse_direct",
                 "use_pass_diffuse_color", "use_pass_glossy_direct", "use_pass_glossy_color",
                 "use_pass_emit", "use_pass_environment", "use_pass_shadow", "use_pass_ambient_occlusion",
                 "use_pass_vector"):
        setattr(view_layer, flag, on)
    cycles = getattr(view_layer, "cycles", None)  # Cycles' own view-layer passes
    if cycles is not None:
        cycles.use_pass_shadow_catcher = on


def bare_setup(scene, world=False):
    """A scene built by a test: a new camera as the scene's, every pass off,
    Cycles on the CPU with direct light only and no denoiser; with ``world``
    a new node World. Returns (camera object, view layer)."""
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    if world:
        scene.world = bpy.data.worlds.new("World")
        scene.world.use_nodes = True
    layer = scene.view_layers[0]
    set_all_passes(layer, False)
    scene.cycles.max_bounces = 0
    scene.cycles.use_denoising = False
    scene.cycles.device = 'CPU'
    return cam, layer


def sphere_in_front(scene, world_color):
    """bare_setup's scene holding a smooth 64-segment unit sphere (pass
    index 1) at the origin, seen from 6 m along +Y at 96x96 with the IndexOB
    pass, under a constant world of ``world_color``; returns the sphere."""
    import math
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)
    cam, layer = bare_setup(scene, world=False)
    scene.world = bpy.data.worlds.new("Constant")
    scene.world.color = world_color
    cam.location = (0.0, -6.0, 0.0)
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.render.resolution_x = scene.render.resolution_y = 96
    scene.render.resolution_percentage = 100
    layer.use_pass_object_index = True
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0)
    sphere = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    sphere.pass_index = 1
    return sphere


def aimed_light(scene, kind, location, energy, size):
    """A light of ``kind`` at ``location`` aimed at the origin: an area
    light ``size`` across, or a point/spot light of radius ``size``."""
    data = bpy.data.lights.new(kind, kind)
    data.energy = energy
    if kind == 'AREA':
        data.size = size
    else:
        data.shadow_soft_size = size
    ob = bpy.data.objects.new(kind, data)
    scene.collection.objects.link(ob)
    ob.location = location
    ob.rotation_euler = (-ob.location).to_track_quat('-Z', 'Y').to_euler()
    return ob


def comparison_setup(scene, size=(160, 90), samples=16):
    """A small render to compare the engines on: ``size`` at 100 %, one
    sample count for Cycles and ours, every pass off; returns the view layer."""
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.cycles.samples = scene.deferred_render.samples = samples
    layer = scene.view_layers[0]
    set_all_passes(layer, False)
    return layer


def render_exr(path_without_ext, scene=None):
    """F12 + save as 32-bit multilayer EXR; returns the file path."""
    scene = scene or bpy.context.scene
    img = scene.render.image_settings
    img.file_format = 'OPEN_EXR_MULTILAYER'
    img.color_depth = '32'
    img.exr_codec = 'ZIP'
    scene.render.use_file_extension = True
    scene.render.filepath = path_without_ext
    bpy.ops.render.render(write_still=True)
    return path_without_ext + ".exr"


def render_combined(scene, engine, samples, path_without_ext, letters="RGBA"):
    """Render with ``engine`` at ``samples`` (Cycles' and ours) into a
    multilayer EXR; returns (Combined as float64 (H, W, len(letters)), IndexOB
    as int64 (H, W) or None), rows bottom-up."""
    scene.render.engine = engine
    scene.cycles.samples = samples
    scene.deferred_render.samples = samples
    channels = read_exr(render_exr(path_without_ext, scene))
    combined = exr_pass(channels, "ViewLayer", "Combined", letters).astype(np.float64)
    index = channels.get("ViewLayer.IndexOB.X")
    return combined, (index.astype(np.int64) if index is not None else None)


def _oiio():
    try:
        import OpenImageIO
    except ImportError as ex:
        raise RuntimeError("reading EXR files needs OpenImageIO's Python module in Blender's Python "
                           "(Debian: apt-get install python3-openimageio)") from ex
    return OpenImageIO


def read_exr(path):
    """{channel name: (H, W) float32 array}, row 0 = BOTTOM (Blender order)."""
    oiio = _oiio()
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(f"cannot open {path}: {oiio.geterror()}")
    try:
        channels = {}
        subimage = 0
        while inp.seek_subimage(subimage, 0):
            spec = inp.spec()
            pixels = inp.read_image(0, spec.nchannels, oiio.FLOAT)
            if pixels is None:
                raise RuntimeError(f"cannot read {path}: {inp.geterror()}")
            pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
            for c, name in enumerate(spec.channelnames):
                channels[name] = pixels[::-1, :, c]
            subimage += 1
    finally:
        inp.close()
    return channels


def exr_size(path):
    oiio = _oiio()
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    size = (spec.width, spec.height)
    inp.close()
    return size


def exr_pass(channels, layer, name, letters):
    """(H, W, C) array of one pass from read_exr() output."""
    return np.stack([channels[f"{layer}.{name}.{c}"] for c in letters], axis=-1)


def expected_channel_names(layer, pass_specs):
    names = set()
    for name, chan_id, _channels in pass_specs:
        for letter in CHANNEL_LETTERS.get(chan_id, chan_id):
            names.add(f"{layer}.{name}.{letter}")
    return names


# ---------------------------------------------------------------------------
# ground truth by ray casting the evaluated scene (Blender's own geometry)
# ---------------------------------------------------------------------------

def camera_rays(scene, camera_object, width, height):
    """World-space ray origins and unit directions through pixel centres.

    Arrays are (H, W, 3) with row 0 = bottom. The frame comes from
    Camera.view_frame(scene), i.e. Blender's own sensor fit, shift and
    aspect handling. Also returns the camera matrix (4x4, scale removed)."""
    cam = camera_object.data
    frame = [np.array(v) for v in cam.view_frame(scene=scene)]  # TR, BR, BL, TL
    right, left = frame[0][0], frame[2][0]
    top, bottom = frame[0][1], frame[1][1]
    z = frame[0][2]
    xs = left + (np.arange(width) + 0.5) / width * (right - left)
    ys = bottom + (np.arange(height) + 0.5) / height * (top - bottom)
    gx, gy = np.meshgrid(xs, ys)
    m = np.array(camera_object.matrix_world, dtype=np.float64)
    for axis in range(3):
        m[:3, axis] /= np.linalg.norm(m[:3, axis])
    rot, pos = m[:3, :3], m[:3, 3]
    if cam.type == 'ORTHO':
        local_origin = np.stack([gx, gy, np.zeros_like(gx)], axis=-1)
        local_dir = np.broadcast_to(np.array([0.0, 0.0, -1.0]), local_origin.shape)
    else:
        local_origin = np.zeros(gx.shape + (3,))
        local_dir = np.stack([gx, gy, np.full_like(gx, z)], axis=-1)
        local_dir = local_dir / np.linalg.norm(local_dir, axis=-1, keepdims=True)
    origins = local_origin @ rot.T + pos
    dirs = np.ascontiguousarray(local_dir @ rot.T)
    return origins, dirs, m


class SceneTriangles:
    """World-space triangles of the evaluated scene with what the passes hold."""

    def __init__(self, bvh, corners, corner_normals, object_index, material_index, names):
        self.bvh = bvh
        self.corners = corners                # (T, 3, 3) world positions
        self.corner_normals = corner_normals  # (T, 3, 3) world split normals
        self.object_index = object_index      # (T,)
        self.material_index = material_index  # (T,) material pass index
        self.names = names

    def shading_normals(self, tri, pos):
        """Interpolated (smooth/split) unit normals at hit points ``pos`` of triangles ``tri``."""
        t = np.maximum(tri, 0)
        a, b, c = (self.corners[t, k] for k in range(3))
        v0, v1, v2 = b - a, c - a, pos - a
        d00 = np.einsum("...i,...i", v0, v0)
        d01 = np.einsum("...i,...i", v0, v1)
        d11 = np.einsum("...i,...i", v1, v1)
        d20 = np.einsum("...i,...i", v2, v0)
        d21 = np.einsum("...i,...i", v2, v1)
        den = np.where(tri >= 0, d00 * d11 - d01 * d01, 1.0)
        w1 = (d11 * d20 - d01 * d21) / den
        w2 = (d00 * d21 - d01 * d20) / den
        w0 = 1.0 - w1 - w2
        n = (w0[..., None] * self.corner_normals[t, 0] + w1[..., None] * self.corner_normals[t, 1]
             + w2[..., None] * self.corner_normals[t, 2])
        return n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-30)


def scene_triangles(depsgraph):
    """SceneTriangles (with a BVH) of every visible mesh instance."""
    from mathutils.bvhtree import BVHTree
    verts, tris, ob_index, ma_index, names, normals = [], [], [], [], [], []
    offset = 0
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.type != 'MESH' or not inst.show_self:
            continue
        mesh = ob.data
        mesh.calc_loop_triangles()
        mesh.calc_normals_split()
        m = np.array(inst.matrix_world)
        co = np.empty(len(mesh.vertices) * 3, np.float64)
        mesh.vertices.foreach_get("co", co)
        co = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
        nt = len(mesh.loop_triangles)
        t = np.empty(nt * 3, np.int64)
        mesh.loop_triangles.foreach_get("vertices", t)
        mi = np.empty(nt, np.int64)
        mesh.loop_triangles.foreach_get("material_index", mi)
        slots = [s.material for s in ob.material_slots]
        mat_pass = np.array([(s.pass_index if s is not None else 0) for s in slots] or [0])
        sn = np.empty(nt * 9, np.float64)
        mesh.loop_triangles.foreach_get("split_normals", sn)
        normal_matrix = np.linalg.inv(m[:3, :3]).T
        sn = sn.reshape(-1, 3) @ normal_matrix.T
        normals.append((sn / np.linalg.norm(sn, axis=1, keepdims=True)).reshape(nt, 3, 3))
        verts.append(co)
        tris.append(t.reshape(-1, 3) + offset)
        ob_index.append(np.full(nt, ob.pass_index))
        ma_index.append(mat_pass[np.clip(mi, 0, len(mat_pass) - 1)])
        names += [ob.name] * nt
        offset += len(co)
    verts = np.concatenate(verts)
    tris = np.concatenate(tris)
    bvh = BVHTree.FromPolygons(verts.tolist(), tris.tolist(), all_triangles=True, epsilon=0.0)
    return SceneTriangles(bvh, verts[tris], np.concatenate(normals), np.concatenate(ob_index),
                          np.concatenate(ma_index), names)


def cast_rays(bvh, origins, dirs, max_dist=1e6):
    """(hit mask, positions, face normals, triangle index) for (H, W, 3) rays."""
    from mathutils import Vector
    h, w, _ = origins.shape
    hit = np.zeros((h, w), bool)
    pos = np.zeros((h, w, 3))
    nrm = np.zeros((h, w, 3))
    tri = np.full((h, w), -1, np.int64)
    ray_cast = bvh.ray_cast
    o_list = origins.reshape(-1, 3).tolist()
    d_list = dirs.reshape(-1, 3).tolist()
    flat_hit = hit.reshape(-1)
    flat_pos = pos.reshape(-1, 3)
    flat_nrm = nrm.reshape(-1, 3)
    flat_tri = tri.reshape(-1)
    for i, (o, d) in enumerate(zip(o_list, d_list)):
        p, n, index, _dist = ray_cast(Vector(o), Vector(d), max_dist)
        if p is not None:
            flat_hit[i] = True
            flat_pos[i] = p
            flat_nrm[i] = n
            flat_tri[i] = index
    return hit, pos, nrm, tri


def interior_mask(labels, radius=1):
    """Pixels whose (2r+1)^2 neighbourhood has one label (away from edges)."""
    h, w = labels.shape
    ok = np.ones((h, w), bool)
    padded = np.pad(labels, radius, mode="edge")
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            ok &= padded[radius + dy:radius + dy + h, radius + dx:radius + dx + w] == labels
    ok[:radius, :] = ok[-radius:, :] = False
    ok[:, :radius] = ok[:, -radius:] = False
    return ok


def rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")

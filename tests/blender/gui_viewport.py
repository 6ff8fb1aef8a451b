"""The Rendered viewport in Blender's real UI (not -b), under Xvfb.

    xvfb-run -a -s "-screen 0 1024x768x24" blender --factory-startup \\
        blend_samples/analytic.blend --addons deferred_render --python tests/blender/gui_viewport.py

The 3D view is switched to Rendered shading looking through the scene
camera (overlays, gizmos and side regions hidden); the script waits for the
accumulation to finish, captures the view's pixels with Blender's own
screenshot operator, and compares the camera frame with a final render of
the same camera and samples. Then, one edit at a time: move an object,
change a material colour, edit a mesh, resize the view. Each time the
image must follow, and the engine's counters (viewport.ViewportSession.stats)
must show what the edit requires: no mesh export and no shader compile for
a move or a colour, one mesh export for a mesh edit, no re-sync for a
resize. Last, a material preview thumbnail is rendered by the engine and is
not empty; closing the Rendered view releases its renderer.

The comparison with the final render. The viewport renders the whole
region with the view's projection, so the camera frame lands on it at a
different size and sub-pixel offset than the render's pixels: only block
means are compared (the frame cut into BLOCKS_X x BLOCKS_Y blocks, each the
mean of the pixels whose centres fall in it, in display values 0..1 after
Blender's view transform, both 8-bit). Per block the two differ by
  - the resampling at edges inside the block: a frame edge placed within
    half a viewport pixel, i.e. coverage off by at most 0.5 / (block width
    in pixels) of the edge's contrast (< 1 for display values): with blocks
    of ~30 viewport pixels, <= 0.017;
  - noise: the same 16 samples at two resolutions. Per-pixel noise of
    this scene's soft shadows is below 0.05 in display values at 16
    samples, and a block averages >= 400 pixels: ~0.0025 (1 sigma);
  - 8-bit rounding: 0.5 / 255 = 0.002 per image.
So MAX_BLOCK_DIFFERENCE = 0.03 per block and MEAN_BLOCK_DIFFERENCE = 0.008
over all blocks (few blocks hold edges). A view drawn without the view
transform (raw linear values) differs by > 0.1 on the floor; a view of
the scene before an edit differs by > 0.05 where the edit is.

Exit status 0 when every check passed (os._exit: Blender's UI would
otherwise keep running).
"""

import os
import sys
import time
import traceback

import bpy
import numpy as np

OUT = os.path.join(os.environ.get("DEFERRED_TEST_OUT") or "/tmp/deferred_test_out", "gui_viewport")
SAMPLES = 16
BLOCKS_X, BLOCKS_Y = 16, 9
MAX_BLOCK_DIFFERENCE = 0.03
MEAN_BLOCK_DIFFERENCE = 0.008
# Pixel for pixel at the same size (step 5): the 8-bit rounding of both
# images (mean |difference| 1/3 of a level) and the viewport's half-float
# texture (relative 2^-11, up to a level after the sRGB curve in the darks)
# keep most pixels within 2/255 and the mean near 1/255. Two kinds of pixels
# may differ by their contrast: those a geometric edge crosses at the pixel
# centre, and those at shadow edges, whose shadow map is sized from the
# visible surfaces' footprint (the view's projection read from Blender's
# float matrix against the camera's own: a texel grid a fraction of a
# texel apart). Both stay under 2 % of the pixels (measured: 1.1 %), adding
# at most ~0.002 to the mean.
PIXEL_MEAN_DIFFERENCE = 0.006
PIXEL_Q98_DIFFERENCE = 2.0 / 255.0 + 1e-6
WAIT_SECONDS = 240

passed, failed = [], []
# Viewports opened and closed for the resource check, and how much the
# process may grow over them: a renderer left behind holds a GL context,
# its targets and a thread (llvmpipe: tens of MiB each).
CYCLES = 3
RSS_GROWTH = 40 * 2**20


def resident():
    """The process's resident memory in bytes."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def check(condition, what, detail=""):
    (passed if condition else failed).append(what)
    print(f"  {'ok  ' if condition else 'FAIL'}  {what}" + (f"  [{detail}]" if detail else ""), flush=True)
    return bool(condition)


def finish():
    print(f"gui_viewport: {len(passed)} passed, {len(failed)} failed", flush=True)
    for what in failed:
        print(f"  failed: {what}", flush=True)
    os._exit(1 if failed else 0)


def view3d():
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == 'VIEW_3D':
                region = next(r for r in area.regions if r.type == 'WINDOW')
                return window, area, region
    raise RuntimeError("no 3D view in the layout")


def read_png(path):
    image = bpy.data.images.load(path, check_existing=False)
    # The stored display values (bytes / 255), not converted to linear.
    image.colorspace_settings.name = 'Non-Color'
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[:, :, :3]  # rows bottom-up


def capture(window, area, region, name):
    """The region's pixels as Blender drew them (display values, rows bottom-up)."""
    path = os.path.join(OUT, f"{name}.png")
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.screen.screenshot_area(filepath=path)
    shot = read_png(path)
    x0, y0 = region.x - area.x, region.y - area.y
    return shot[y0:y0 + region.height, x0:x0 + region.width]


def final_render(name):
    """The final render of the scene camera, saved with the view transform."""
    scene = bpy.context.scene
    bpy.ops.render.render()
    path = os.path.join(OUT, f"{name}_final.png")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    return read_png(path)


def camera_frame(region, region_data):
    """The camera frame's rectangle in region pixels (x0, y0, x1, y1)."""
    from bpy_extras.view3d_utils import location_3d_to_region_2d
    scene = bpy.context.scene
    camera = scene.camera
    corners = [camera.matrix_world @ c for c in camera.data.view_frame(scene=scene)]
    points = [location_3d_to_region_2d(region, region_data, c) for c in corners]
    xs, ys = [p.x for p in points], [p.y for p in points]
    return min(xs), min(ys), max(xs), max(ys)


def block_means(image, rect):
    """Means of the pixels whose centres fall in each of the blocks of rect
    (x0, y0, x1, y1 in the image's pixel coordinates), shape (BY, BX, 3)."""
    x0, y0, x1, y1 = rect
    height, width = image.shape[:2]
    cx = (np.arange(width) + 0.5 - x0) / (x1 - x0) * BLOCKS_X
    cy = (np.arange(height) + 0.5 - y0) / (y1 - y0) * BLOCKS_Y
    out = np.zeros((BLOCKS_Y, BLOCKS_X, 3))
    for by in range(BLOCKS_Y):
        rows = (cy >= by) & (cy < by + 1)
        for bx in range(BLOCKS_X):
            cols = (cx >= bx) & (cx < bx + 1)
            out[by, bx] = image[rows][:, cols].reshape(-1, 3).mean(axis=0)
    return out


def compare_with_final(view, rect, final, what):
    ours = block_means(view, rect)
    ref = block_means(final, (0, 0, final.shape[1], final.shape[0]))
    diff = np.abs(ours - ref)
    check(diff.max() <= MAX_BLOCK_DIFFERENCE and diff.mean() <= MEAN_BLOCK_DIFFERENCE,
          f"{what}: the viewport's camera frame matches the final render",
          f"block difference max {diff.max():.4f} (<= {MAX_BLOCK_DIFFERENCE}), "
          f"mean {diff.mean():.4f} (<= {MEAN_BLOCK_DIFFERENCE})")
    return ours


def steps():
    os.makedirs(OUT, exist_ok=True)
    from deferred_render.engine import viewport
    scene = bpy.context.scene
    scene.render.engine = 'DEFERRED_RENDER'
    scene.deferred_render.samples = SAMPLES
    scene.deferred_render.viewport_samples = SAMPLES
    scene.render.image_settings.file_format = 'PNG'
    scene.render.image_settings.color_mode = 'RGB'
    scene.camera.data.show_passepartout = False
    # Not rendered by this engine (final render or viewport): must be named.
    scene.camera.data.dof.use_dof = True
    # Side regions take their width from the view (not drawn over it), so
    # showing the sidebar resizes the view's region.
    bpy.context.preferences.system.use_region_overlap = False
    window, area, region = view3d()
    space = area.spaces.active
    for attr in ("show_region_header", "show_region_toolbar", "show_region_ui", "show_region_tool_header",
                 "show_gizmo"):
        setattr(space, attr, False)
    space.overlay.show_overlays = False
    space.shading.type = 'RENDERED'
    region_data = space.region_3d
    region_data.view_perspective = 'CAMERA'
    yield
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.view3d.view_center_camera()
    yield

    def session():
        live = viewport.sessions()
        return live[0] if live else None

    def wait_done(what, after=None):
        """Until the accumulation after the edit (a generation newer than
        `after`) has drawn its last sample."""
        start = time.perf_counter()
        while time.perf_counter() - start < WAIT_SECONDS:
            s = session()
            if after is not None and (s is None or s.generation <= after):
                yield
                continue
            if s is not None and s.error:
                check(False, f"{what}: the viewport rendered", s.error)
                finish()
            if (s is not None and s.samples_total and s.samples_done == s.samples_total
                    and s.shown_generation == s.generation and not (s._worker and s._worker.is_alive())):
                return s
            yield
        check(False, f"{what}: the viewport finished within {WAIT_SECONDS} s")
        finish()

    s = yield from wait_done("first display")
    check(len(viewport.sessions()) == 1, "one viewport session", str(len(viewport.sessions())))
    # The camera's depth of field (set above) is not rendered: named.
    check(any("depth of field" in w for w in s.warnings), "the camera view names what it does not render",
          repr(s.warnings))
    first_stats = dict(s.stats)
    check(first_stats.get("meshes_exported") == 6, "the first sync exports the scene's 6 meshes", str(first_stats))
    view = capture(window, area, region, "view_first")
    rect = camera_frame(region, region_data)
    print(f"  camera frame in the region: {rect}", flush=True)
    check(view.shape[:2] == (region.height, region.width), "the capture is the view's region",
          f"{view.shape[1]}x{view.shape[0]} vs {region.width}x{region.height}")
    before_move = compare_with_final(view, rect, final_render("first"), "first display")

    # 1. Move an object: a transform, no mesh export, no compile.
    stats = dict(s.stats)
    bpy.data.objects["Box"].location.x += 0.6
    s = yield from wait_done("object moved", after=s.generation)
    delta = {k: s.stats[k] - stats.get(k, 0) for k in s.stats}
    check(delta.get("syncs", 0) >= 1 and delta.get("meshes_exported", 0) == 0
          and delta.get("meshes_reused", 0) >= 6 and delta.get("programs_compiled", 0) == 0
          and delta.get("meshes_uploaded", 0) == 0,
          "moving an object re-syncs with every mesh kept: no mesh export or upload, no compile", str(delta))
    print(f"  edit -> first sample on screen: {s.first_sample_seconds:.3f} s", flush=True)
    view = capture(window, area, region, "view_moved")
    after_move = compare_with_final(view, rect, final_render("moved"), "after the move")
    check(np.abs(after_move - before_move).max() > 0.05, "the view follows the move",
          f"largest block change {np.abs(after_move - before_move).max():.3f}")

    # 2. A material colour: constants only.
    stats = dict(s.stats)
    material = bpy.data.materials["MatSphereB"]
    principled = next(n for n in material.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    principled.inputs["Base Color"].default_value = (0.8, 0.05, 0.02, 1.0)
    s = yield from wait_done("material colour", after=s.generation)
    delta = {k: s.stats[k] - stats.get(k, 0) for k in s.stats}
    check(delta.get("meshes_exported", 0) == 0 and delta.get("programs_compiled", 0) == 0
          and delta.get("syncs", 0) >= 1,
          "a material colour re-syncs without mesh export or compile", str(delta))
    view = capture(window, area, region, "view_colour")
    after_colour = compare_with_final(view, rect, final_render("colour"), "after the colour edit")
    redder = (after_colour[..., 0] - after_colour[..., 2]) - (after_move[..., 0] - after_move[..., 2])
    check(redder.max() > 0.2, "the view follows the colour (SphereB turns red)", f"largest red-blue gain {redder.max():.3f}")

    # 3. A mesh edit: that mesh only. Then undone: the view shows the mesh
    # as it was (an undo reloads the changed mesh; a stale kept mesh would
    # show the edit).
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.ed.undo_push(message="before the mesh edit")
    stats = dict(s.stats)
    box = bpy.data.objects["Box"]
    for vertex in box.data.vertices:
        if vertex.co.z > 0:
            vertex.co.z += 0.4
    box.data.update()
    s = yield from wait_done("mesh edit", after=s.generation)
    delta = {k: s.stats[k] - stats.get(k, 0) for k in s.stats}
    check(delta.get("meshes_exported", 0) == 1 and delta.get("meshes_reused", 0) >= 5,
          "editing a mesh exports that mesh only", str(delta))
    view = capture(window, area, region, "view_mesh")
    after_mesh = compare_with_final(view, rect, final_render("mesh"), "after the mesh edit")
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.ed.undo_push(message="the mesh edit")
        bpy.ops.ed.undo()
    s = yield from wait_done("undo", after=s.generation)
    # An undo reloads data-blocks: every Python reference is found again.
    scene = bpy.context.scene
    material = bpy.data.materials["MatSphereB"]
    window, area, region = view3d()
    space = area.spaces.active
    region_data = space.region_3d
    view = capture(window, area, region, "view_undo")
    undone = block_means(view, rect)
    check(np.abs(undone - after_colour).max() <= MAX_BLOCK_DIFFERENCE
          and np.abs(after_mesh - after_colour).max() > 0.05,
          "undoing the mesh edit shows the mesh as it was",
          f"largest block difference to before the edit {np.abs(undone - after_colour).max():.4f}, "
          f"the edit had changed blocks by {np.abs(after_mesh - after_colour).max():.3f}")

    # 4. The view's size: a restart at the new size, no re-sync.
    stats = dict(s.stats)
    old_width = region.width
    space.show_region_ui = True  # the sidebar takes part of the region
    s = yield from wait_done("resize", after=s.generation)
    delta = {k: s.stats[k] - stats.get(k, 0) for k in s.stats}
    check(region.width < old_width and s._texture_size == (region.width, region.height),
          "the view follows a resize (an image of the region's new size)",
          f"{old_width} -> {region.width}, image {s._texture_size}")
    check(delta.get("syncs", 0) == 0 and delta.get("restarts", 0) >= 1,
          "a resize restarts the accumulation without a re-sync", str(delta))
    space.show_region_ui = False
    yield

    # 5. Free perspective and orthographic views, pixel for pixel against a
    # final render through a camera built from Blender's own view
    # parameters as Cycles reads them (blender_camera_from_view: the view's
    # lens on a 36 mm sensor, ortho_scale = distance x 36 / lens for
    # orthographic with its clip range centred on the view, and a zoom of 2
    # for both), at the
    # region's size: the same pixels and samples, so they differ by the
    # viewport texture's half floats and 8-bit rounding (1/255 per pixel),
    # and at edges where float rounding puts a pixel centre on the other side.
    from mathutils import Euler, Vector
    region_data.view_perspective = 'PERSP'
    region_data.view_location = (0.0, 0.0, 0.6)
    region_data.view_rotation = Euler((1.15, 0.0, 0.5)).to_quaternion()
    region_data.view_distance = 11.0
    for kind in ('PERSP', 'ORTHO'):
        region_data.view_perspective = kind
        s = yield from wait_done(f"{kind} view", after=s.generation)
        view = capture(window, area, region, f"view_{kind.lower()}")
        camera_data = bpy.data.cameras.new(f"View{kind}")
        camera = bpy.data.objects.new(f"View{kind}", camera_data)
        scene.collection.objects.link(camera)
        matrix = region_data.view_matrix.inverted()
        if kind == 'PERSP':
            camera_data.lens = space.lens
            camera_data.sensor_width = 72.0
            camera_data.clip_start, camera_data.clip_end = space.clip_start, space.clip_end
        else:
            camera_data.type = 'ORTHO'
            # Cycles' blender_camera_from_view: zoom 2 for every free view.
            camera_data.ortho_scale = 2.0 * region_data.view_distance * 36.0 / space.lens
            # The clip range [-clip_end / 2, clip_end / 2] around the view,
            # from a camera behind it whose range starts where the engine's
            # does (viewport.MIN_CLIP_START: sun cascades split from there).
            near = viewport.MIN_CLIP_START
            back = space.clip_end * 0.5 + near
            matrix.translation = matrix.translation + matrix.to_3x3() @ Vector((0.0, 0.0, back))
            camera_data.clip_start, camera_data.clip_end = near, space.clip_end + near
        camera_data.sensor_fit = 'AUTO'
        camera.matrix_world = matrix
        old_camera, scene.camera = scene.camera, camera
        old_size = (scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage)
        scene.render.resolution_x, scene.render.resolution_y = region.width, region.height
        scene.render.resolution_percentage = 100
        reference = final_render(f"view_{kind.lower()}")
        scene.camera = old_camera
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = old_size
        difference = np.abs(view - reference).max(axis=2) if view.shape == reference.shape else None
        check(difference is not None and difference.mean() <= PIXEL_MEAN_DIFFERENCE
              and np.quantile(difference, 0.98) <= PIXEL_Q98_DIFFERENCE,
              f"{kind} view: the viewport equals a final render of the same view pixel for pixel",
              "sizes differ" if difference is None else
              f"mean {difference.mean():.4f} (<= {PIXEL_MEAN_DIFFERENCE}), 98th percentile "
              f"{np.quantile(difference, 0.98):.4f} (<= {PIXEL_Q98_DIFFERENCE:.4f})")
        yield

    # 6. The Render Pass menu (View3DShading.deferred_render.render_pass):
    # the view shows the pass; then a render border crops the view.
    combined_view = view
    space.shading.deferred_render.render_pass = 'Normal'
    s = yield from wait_done("Normal pass", after=s.generation)
    normals = s._pixels
    lengths = np.linalg.norm(normals[..., :3], axis=2)
    geometry = lengths > 0.5
    # Normals are averaged over the samples: shorter on edges, where the
    # samples see different surfaces.
    spread = np.quantile(np.abs(lengths[geometry] - 1.0), 0.95)
    check(geometry.mean() > 0.3 and spread < 0.02 and np.all(normals[..., 3] == 1.0),
          "the Render Pass menu shows the Normal pass (unit normals on geometry, opaque)",
          f"geometry {geometry.mean():.2f} of the view, 95 % of |n| within {spread:.4f} of 1")
    space.shading.deferred_render.render_pass = 'Combined'
    s = yield from wait_done("Combined pass again", after=s.generation)
    space.use_render_border = True
    space.render_border_min_x, space.render_border_max_x = 0.25, 0.75
    space.render_border_min_y, space.render_border_max_y = 0.3, 0.8
    for _ in range(3):
        yield
    bordered = capture(window, area, region, "view_border")
    full = combined_view  # the same view and samples, without a border
    x0, x1 = int(0.25 * region.width) + 2, int(0.75 * region.width) - 2
    y0, y1 = int(0.3 * region.height) + 2, int(0.8 * region.height) - 2
    inside = np.abs(bordered[y0:y1, x0:x1] - full[y0:y1, x0:x1]).max()
    # Outside (below the border): the view's dark background (Blender's
    # theme, a dithered grey below 0.3), where the full view shows the lit
    # floor.
    rows = slice(0, int(0.3 * region.height) - 2)
    outside, was = bordered[rows].max(axis=2), full[rows].max(axis=2)
    check(inside <= 2.0 / 255 + 1e-6 and outside.max() < 0.3 and (was > 0.5).mean() > 0.25,
          "a render border shows the image inside it and nothing outside",
          f"inside difference {inside:.4f}; below it at most {outside.max():.3f}, where the view "
          f"without border is lit (> 0.5) on {(was > 0.5).mean():.0%} of the pixels")
    space.use_render_border = False
    yield

    # 7. Material and world preview thumbnails, rendered by this engine.
    from deferred_render.engine import final

    def thumbnail(datablock):
        """Asks Blender for the data-block's preview; yields until this
        engine has rendered it; returns (preview renders, pixels or None)."""
        before = final.preview_renders
        datablock.preview_ensure()
        with bpy.context.temp_override(window=window, area=area, region=region, id=datablock):
            bpy.ops.ed.lib_id_generate_preview()
        start = time.perf_counter()
        while time.perf_counter() - start < WAIT_SECONDS:
            preview = datablock.preview
            if final.preview_renders > before and preview.image_size[0] > 0:
                pixels = np.array(preview.image_pixels_float[:], dtype=np.float32)
                if pixels.max() > 0:
                    return final.preview_renders - before, pixels
            yield
        return final.preview_renders - before, None

    renders, pixels = yield from thumbnail(material)
    check(renders > 0, "the material preview was rendered by this engine", f"{renders} preview renders")
    check(pixels is not None and pixels.max() > 0.05 and pixels.reshape(-1, 4)[:, :3].std() > 0.01,
          "the preview thumbnail is not empty",
          "no pixels" if pixels is None else f"max {pixels.max():.3f}, std {pixels.reshape(-1, 4)[:, :3].std():.3f}")
    renders, pixels = yield from thumbnail(scene.world)
    check(renders > 0 and pixels is not None and pixels.max() > 0.01,
          "the world preview thumbnail is rendered by this engine and not empty",
          "no pixels" if pixels is None else f"max {pixels.max():.3f}")

    # 8. Resources: leaving Rendered mode frees the engine and its renderer,
    # also after many viewports came and went, after switching engines, after
    # reloading the file and after disabling the add-on.
    # The final render's renderer (the F12 above) stays with its context and
    # programs (engine/session.py): the one renderer not the viewport's.
    from deferred_render import native
    from deferred_render.engine import session as final_session
    mod = native.load()

    def released(what, rss_before=None):
        for _ in range(20):
            yield
            if not viewport.sessions() and mod.live_renderers() == final_session.renderers_held():
                break
        detail = (f"{len(viewport.sessions())} sessions, {mod.live_renderers()} native renderers alive, "
                  f"{final_session.renderers_held()} of them the final render's")
        if rss_before is not None:
            detail += f", resident memory {rss_before / 2**20:.0f} -> {resident() / 2**20:.0f} MiB"
        check(not viewport.sessions() and mod.live_renderers() == final_session.renderers_held(),
              f"{what} releases the viewport's renderer", detail)

    space.shading.type = 'SOLID'
    yield from released("leaving Rendered shading")
    rss = resident()
    for _ in range(CYCLES):
        space.shading.type = 'RENDERED'
        s = yield from wait_done("a viewport opened again")
        space.shading.type = 'SOLID'
        yield from released("closing it")
    check(resident() - rss < RSS_GROWTH, f"{CYCLES} viewports opened and closed do not grow the process",
          f"{(resident() - rss) / 2**20:.1f} MiB (< {RSS_GROWTH / 2**20:.0f} MiB)")
    space.shading.type = 'RENDERED'
    s = yield from wait_done("before switching engines")
    scene.render.engine = 'BLENDER_WORKBENCH'
    yield from released("switching the engine")
    scene.render.engine = 'DEFERRED_RENDER'
    s = yield from wait_done("before reloading the file")
    with bpy.context.temp_override(window=window):
        bpy.ops.wm.revert_mainfile()
    yield from released("reloading the file")
    # The reloaded file's own UI: find the view again, render in it again.
    scene = bpy.context.scene
    window, area, region = view3d()
    space = area.spaces.active
    scene.render.engine = 'DEFERRED_RENDER'
    space.shading.type = 'RENDERED'
    s = yield from wait_done("before disabling the add-on")
    import addon_utils
    addon_utils.disable("deferred_render")
    yield from released("disabling the add-on")
    finish()


_steps = None


def tick():
    global _steps
    try:
        if _steps is None:
            _steps = steps()
        next(_steps)
    except StopIteration:
        finish()
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        os._exit(1)
    return 0.2


# persistent: the timer outlives the file reload of step 8.
bpy.app.timers.register(tick, first_interval=0.5, persistent=True)

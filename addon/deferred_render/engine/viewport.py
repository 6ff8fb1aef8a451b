"""The Rendered viewport: 3D View > Viewport Shading > Rendered.

One ``ViewportSession`` per viewport engine (Blender makes a RenderEngine
per 3D view in Rendered mode). It owns a native renderer (its own EGL
context on its own render thread) and runs each accumulation on a worker
thread, so Blender's UI never waits for samples:

- ``view_update`` (Blender calls it after every depsgraph change): stops the
  accumulation, re-syncs the scene and marks a restart. The sync is the
  final render's export, with meshes kept by the renderer between syncs
  (``export.MeshKeeper``): moving an object or a light, or editing a
  material, exports no mesh (the renderer finds it by key); editing a mesh
  re-exports that mesh only; node-material programs come from the
  renderer's program cache (a value edit changes constants, not code).
- ``view_draw``: builds the view's camera from the region (its own
  projection, ``region_data.window_matrix``: perspective, orthographic and
  camera view with its zoom and offset), restarts the accumulation when the
  camera or the region size changed, and draws the newest accumulated image
  the renderer published (``Renderer.preview``, which never waits for the
  render thread) through Blender's colour management
  (``bind_display_space_shader``). It tags a redraw while samples remain;
  after the last one nothing runs until the next change.

``sessions()`` lists the live sessions and ``ViewportSession.stats`` counts
what each sync and restart did, for tests and the benchmark.
"""

import collections
import threading
import time
import weakref

import numpy as np

from .. import native
from ..export import MeshKeeper, export_scene
from ..export import camera as camera_export
from . import final

# How often the renderer publishes the accumulating image (the first sample
# always, and the last): the viewport's refresh while it converges.
PREVIEW_INTERVAL_MS = 100
# Nearest clip plane the renderer accepts (camera.cpp); an orthographic
# view's clip range starts behind the view (-clip_end / 2), so its camera
# is moved back along its axis until the range starts here (the same
# orthographic projection).
MIN_CLIP_START = 1e-5

_sessions = weakref.WeakSet()


def sessions():
    """The live viewport sessions (one per 3D view in Rendered mode)."""
    return list(_sessions)


def view_camera(region_data, width, height):
    """Keyword arguments of ``deferred_native.Camera`` for the 3D view:
    the inverse of its view matrix, and the viewplane and clip range read
    from its projection (``window_matrix``, a glFrustum/glOrtho matrix,
    which in camera view holds the camera's projection with the view's
    zoom and offset)."""
    view = np.array(region_data.view_matrix, dtype=np.float64)
    p = np.array(region_data.window_matrix, dtype=np.float64)
    if not (np.isfinite(view).all() and np.isfinite(p).all()) or width <= 0 or height <= 0:
        raise camera_export.CameraError("the 3D view has no valid projection")
    matrix = np.linalg.inv(view)
    for axis in range(3):  # rotation only, as the final render's camera
        matrix[:3, axis] /= np.linalg.norm(matrix[:3, axis])
    if region_data.is_perspective:
        # x_ndc = p00 x/d - p02 (d = -z_view): at unit distance the view
        # spans (ndc + p02) / p00 for ndc in [-1, 1].
        left, right = (-1.0 + p[0, 2]) / p[0, 0], (1.0 + p[0, 2]) / p[0, 0]
        bottom, top = (-1.0 + p[1, 2]) / p[1, 1], (1.0 + p[1, 2]) / p[1, 1]
        near, far = p[2, 3] / (p[2, 2] - 1.0), p[2, 3] / (p[2, 2] + 1.0)
        kind = "PERSP"
    else:
        left, right = (-1.0 - p[0, 3]) / p[0, 0], (1.0 - p[0, 3]) / p[0, 0]
        bottom, top = (-1.0 - p[1, 3]) / p[1, 1], (1.0 - p[1, 3]) / p[1, 1]
        near, far = (p[2, 3] + 1.0) / p[2, 2], (p[2, 3] - 1.0) / p[2, 2]
        kind = "ORTHO"
        if near < MIN_CLIP_START:
            back = MIN_CLIP_START - near
            matrix[:3, 3] += matrix[:3, 2] * back  # the view looks down -Z
            near, far = near + back, far + back
    if not (far > near > 0.0):
        raise camera_export.CameraError(f"the 3D view's clip range {near:g} .. {far:g} is empty")
    return {"type": kind, "matrix": matrix, "clip_start": float(near), "clip_end": float(far),
            "viewplane": (float(left), float(right), float(bottom), float(top))}


def render_border(context, scene, width, height):
    """The part of the region the viewport shows (x0, y0, x1, y1 in region
    pixels), or None for all of it, as Cycles' viewport does: in camera
    view the scene's Render Region (Output > Format > Render Region) within
    the camera frame, otherwise the view's own render border (View > Render
    Region, Ctrl B). The accumulation covers the whole region; only the
    border is drawn."""
    space, region_data = context.space_data, context.region_data
    if region_data.view_perspective == 'CAMERA':
        render = scene.render
        if not render.use_border or scene.camera is None or scene.camera.type != 'CAMERA':
            return None
        from bpy_extras.view3d_utils import location_3d_to_region_2d
        camera = scene.camera
        corners = [camera.matrix_world @ c for c in camera.data.view_frame(scene=scene)]
        points = [location_3d_to_region_2d(context.region, region_data, c) for c in corners]
        if any(p is None for p in points):
            return None
        fx0, fx1 = min(p.x for p in points), max(p.x for p in points)
        fy0, fy1 = min(p.y for p in points), max(p.y for p in points)
        box = (fx0 + render.border_min_x * (fx1 - fx0), fy0 + render.border_min_y * (fy1 - fy0),
               fx0 + render.border_max_x * (fx1 - fx0), fy0 + render.border_max_y * (fy1 - fy0))
    else:
        if not getattr(space, "use_render_border", False):
            return None
        box = (space.render_border_min_x * width, space.render_border_min_y * height,
               space.render_border_max_x * width, space.render_border_max_y * height)
    x0, y0 = max(0, int(round(box[0]))), max(0, int(round(box[1])))
    x1, y1 = min(width, int(round(box[2]))), min(height, int(round(box[3])))
    return (x0, y0, max(x0, x1), max(y0, y1))


class ViewportSession:
    """The state of one viewport engine (see the module docstring)."""

    def __init__(self, engine):
        self._engine = weakref.ref(engine)
        self.mod = None
        self.renderer = None
        self.keeper = MeshKeeper()
        self.synced = False
        self._fresh_sync = False    # no accumulation has run since the last sync
        self._scene_signature = None  # what a scene update without flags may change: its world
        self.error = None           # a message shown in the viewport instead of an image
        self.warnings = []
        self.last_sync = ""         # what the last sync did, for the viewport's status text
        self._worker = None
        self._restart = True
        self._view = None           # (camera params, width, height, settings) of the running accumulation
        self._version = 0           # newest preview version drawn
        self._texture = None
        self._texture_border = None  # the region rectangle the texture covers (None: all)
        self._texture_size = None     # the accumulation's size
        self._pixels = None           # the newest image taken from the renderer
        self.samples_done = 0
        self.samples_total = 0
        self.generation = 0         # accumulations started
        self.shown_generation = -1  # the generation whose image is on screen
        self.change_time = None     # when the change that started this generation arrived
        self.first_sample_seconds = None  # change -> first sample of it drawn
        self.stats = collections.Counter()
        _sessions.add(self)

    # -- lifetime ---------------------------------------------------------
    def free(self):
        """Stop the accumulation and release the renderer (its GL context
        and every GPU resource): the engine is going away."""
        self.stop()
        self._texture = self._pixels = None
        renderer, self.renderer = self.renderer, None
        if renderer is not None:
            renderer.close()
        _sessions.discard(self)

    def stop(self):
        """Cancel the running accumulation and wait for it (at most one
        stage of a sample: the renderer checks for cancellation before its
        shadow maps, before its lighting and between samples)."""
        worker = self._worker
        if worker is None:
            return
        if worker.is_alive():
            start = time.perf_counter()
            # Repeated: a render that starts clears a cancel issued before it
            # (the worker may not have reached render() yet).
            while worker.is_alive():
                self.renderer.cancel()
                worker.join(0.02)
            # How long the UI waited for the running stage (the benchmark's
            # "UI wait on an edit").
            waited = time.perf_counter() - start
            self.stats["stops"] += 1
            self.stats["stop_seconds_max"] = max(self.stats["stop_seconds_max"], waited)
        self._worker = None

    def _status(self, text):
        engine = self._engine()
        if engine is not None:
            engine.update_stats("", text)

    # -- view_update ------------------------------------------------------
    def update(self, context, depsgraph):
        """A depsgraph change (or the first display): re-sync the scene."""
        import bpy
        changed = not self.synced
        for update in depsgraph.updates:
            datablock = update.id
            flags = (update.is_updated_geometry, update.is_updated_transform, update.is_updated_shading)
            if isinstance(datablock, bpy.types.Scene) and not any(flags):
                # The scene itself, tagged without geometry, transform or
                # shading (a final render, a UI change, a render setting):
                # the settings the accumulation reads are compared in
                # view_draw; the world the scene points to is below. Known
                # gap: a view-layer setting the export reads (a holdout
                # collection) changes nothing here until the next edit.
                continue
            changed = True
            if update.is_updated_geometry:
                self._geometry_changed(datablock, depsgraph)
        world = depsgraph.scene.world
        signature = world.name_full if world is not None else None
        if signature != self._scene_signature:
            self._scene_signature = signature
            changed = True
        if not changed:
            return
        self.change_time = time.perf_counter()
        self.stop()
        try:
            if self.renderer is None:
                self.mod = native.load()
                settings = getattr(depsgraph.scene, "deferred_render", None)
                device_index = int(getattr(settings, "device_index", -1)) if settings is not None else -1
                self.renderer = self.mod.Renderer(device_index=device_index)
            self.warnings = []
            start = time.perf_counter()
            self.keeper.begin_sync()
            stats, _ = export_scene(depsgraph, self.renderer, warn=self._warn, mesh_keeper=self.keeper)
            self.keeper.end_sync()
            self.stats["syncs"] += 1
            self.stats["meshes_exported"] += stats.meshes
            self.stats["meshes_reused"] += stats.meshes_reused
            self.last_sync = f"sync: {stats.meshes} meshes exported, {stats.meshes_reused} kept"
            self.stats["sync_seconds"] += time.perf_counter() - start
            self.synced = True
            self._fresh_sync = True
            self.error = None
        except Exception as ex:  # shown in the viewport; never raised into Blender
            self.error = str(ex) or type(ex).__name__
            final.last_messages.append(('ERROR', f"{final.LOG_PREFIX}: viewport: {self.error}"))
            self.synced = False
        self._restart = True

    def _warn(self, message):
        self.warnings.append(message)
        final.last_messages.append(('WARNING', f"{final.LOG_PREFIX}: viewport: {message}"))

    def _geometry_changed(self, datablock, depsgraph):
        """Geometry edits give the object's meshes new keys (exported again)."""
        import bpy
        if isinstance(datablock, bpy.types.Object):
            self.keeper.geometry_changed(MeshKeeper.object_name(datablock))
        else:
            # A mesh, curve or other data edited: every object using it.
            original = getattr(datablock, "original", None) or datablock
            for ob in depsgraph.scene.objects:
                if ob.data is not None and ob.data == original:
                    self.keeper.geometry_changed(ob.name_full)

    # -- view_draw --------------------------------------------------------
    def draw(self, context, depsgraph):
        try:
            self._draw(context, depsgraph)
        except Exception as ex:  # shown in the viewport; never raised into Blender
            self.error = str(ex) or type(ex).__name__
            self._status(f"{final.LOG_PREFIX}: {self.error}")

    def _draw(self, context, depsgraph):
        import gpu
        from gpu_extras.presets import draw_texture_2d

        engine = self._engine()
        if engine is None:
            return
        region = context.region
        width, height = int(region.width), int(region.height)
        scene = depsgraph.scene
        if self.synced:
            # Also after an error: a new view or setting tries again (an
            # accumulation that failed is not retried for the same view).
            try:
                self._ensure_running(context.region_data, width, height, scene,
                                     getattr(context.space_data, "shading", None))
            except Exception as ex:
                self.error = str(ex) or type(ex).__name__
        if self.error is not None:
            self._status(f"{final.LOG_PREFIX}: {self.error}")
            return
        self._take_preview()
        border = render_border(context, scene, width, height)
        if self._texture_size != (width, height):
            # The accumulation at the new size has no sample yet: the last
            # image, stretched over the region meanwhile, uncropped.
            border = None
        if self._pixels is not None and (self._texture is None or self._texture_border != border):
            self._make_texture(border)
        if self._texture is not None:
            x0, y0, x1, y1 = self._texture_border or (0, 0, width, height)
            gpu.state.blend_set('ALPHA_PREMULT')
            engine.bind_display_space_shader(scene)
            draw_texture_2d(self._texture, (x0, y0), x1 - x0, y1 - y0)
            engine.unbind_display_space_shader()
            gpu.state.blend_set('NONE')
        running = self._worker is not None and self._worker.is_alive()
        if running or self.samples_done < self.samples_total or self.shown_generation != self.generation:
            engine.tag_redraw()
        if self.error is None:
            self._status(f"Sample {self.samples_done}/{self.samples_total} | {self.last_sync}"
                         + (f" | {len(self.warnings)} warnings (see the console)" if self.warnings else ""))

    def _settings(self, scene, shading):
        settings = getattr(scene, "deferred_render", None)
        samples = int(getattr(settings, "viewport_samples", 32)) if settings is not None else 32
        view_settings = getattr(shading, "deferred_render", None)
        shown = str(getattr(view_settings, "render_pass", "Combined")) if view_settings is not None else "Combined"
        passes = ["Combined"] if shown == "Combined" else ["Combined", shown]
        return dict(passes=passes, film_transparent=bool(scene.render.film_transparent),
                    samples=max(1, samples), filter_width=final._filter_width(scene),
                    filter_splat=final._filter_splat(scene),
                    visibility_buffer=final._visibility_buffer(scene),
                    preview_interval_ms=PREVIEW_INTERVAL_MS, preview_pass=shown,
                    **final._light_settings(scene))

    def _ensure_running(self, region_data, width, height, scene, shading):
        params = view_camera(region_data, width, height)
        settings = self._settings(scene, shading)
        key = (repr(sorted((k, np.asarray(v).tolist()) for k, v in params.items())), width, height,
               repr(sorted(settings.items())))
        if key == self._view and not self._restart:
            return
        if key != self._view and self.change_time is None:
            self.change_time = time.perf_counter()
        self.stop()
        self._take_preview(counted=False)  # what the stopped accumulation left: still the old view
        self._view = key
        self._restart = False
        self.error = None
        self.generation += 1
        self.samples_done = 0
        self.samples_total = settings["samples"]
        self.stats["restarts"] += 1
        if region_data.view_perspective == 'CAMERA' and scene.camera is not None:
            # What the camera has that the view's projection leaves out
            # (panoramic types, depth of field): named, as a final render does.
            try:
                _, camera_warnings = camera_export.camera_params(scene, scene.camera)
            except camera_export.CameraError as ex:
                camera_warnings = [str(ex)]
            for message in camera_warnings:
                if message not in self.warnings:
                    self._warn(message)
        camera = self.mod.Camera(**params)
        renderer = self.renderer
        first_after_sync, self._fresh_sync = self._fresh_sync, False

        def work():
            try:
                renderer.render(camera, width, height, **settings)
                timings = dict(renderer.last_timings)
                self.stats["programs_compiled"] += int(timings.get("programs_compiled", 0))
                if first_after_sync:  # the renderer counts uploads since the sync
                    self.stats["meshes_uploaded"] += int(timings.get("meshes_uploaded", 0))
            except Exception as ex:
                if not isinstance(ex, getattr(self.mod, "Cancelled", ())):
                    self.error = str(ex) or type(ex).__name__

        self._worker = threading.Thread(target=work, name="deferred-viewport", daemon=True)
        self._worker.start()

    def _make_texture(self, border):
        import gpu
        pixels = self._pixels
        if border is not None:
            x0, y0, x1, y1 = border
            pixels = pixels[y0:y1, x0:x1]
        pixels = np.ascontiguousarray(pixels)
        if pixels.size == 0:
            self._texture, self._texture_border = None, border
            return
        buffer = gpu.types.Buffer('FLOAT', pixels.size, pixels.reshape(-1))
        self._texture = gpu.types.GPUTexture((pixels.shape[1], pixels.shape[0]), format='RGBA16F', data=buffer)
        self._texture_border = border

    def _take_preview(self, counted=True):
        image = self.renderer.preview(self._version) if self.renderer is not None else None
        if image is None:
            return
        version, done, total, pixels = image
        self._version = version
        if pixels is None:
            return  # the new accumulation has no sample yet: keep the old image
        self._pixels = pixels
        self._texture = None  # made in draw, cropped to the render border
        self._texture_size = (pixels.shape[1], pixels.shape[0])
        if not counted:
            return
        self.samples_done, self.samples_total = done, total
        if self.shown_generation != self.generation:
            self.shown_generation = self.generation
            if self.change_time is not None:
                self.first_sample_seconds = time.perf_counter() - self.change_time
                self.change_time = None
        self.stats["images_drawn"] += 1

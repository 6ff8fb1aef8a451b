"""Final render (F12, ``blender -b -f/-a``): one call per view layer.

Stages, with ``test_break()`` between each:
  1. begin the render result (so every exit leaves a valid result)
  2. start the native renderer (own EGL context on its own thread), or take
     back the one kept by the previous render (Persistent Data, session.py)
  3. export the depsgraph (export/)
  4. render the passes registered for this view layer
  5. write every pass with ONE ``layer.passes.foreach_set("rect", flat)``
     (the per-pass ``rect.foreach_set`` is broken on 3.4.1)

Any exception becomes ``report({'ERROR'}, ...)`` and the (zero-filled)
result is still ended, so Blender writes an empty but valid image and goes
on; in ``finally`` the native session is kept for the next render when
the render succeeded (with its data when Persistent Data is on, else its
GL context and programs only; session.py) and released when it failed.
"""

import collections
import math
import sys
import threading
import time
import traceback

from .. import native
from . import capture, session
from ..export import camera as camera_export
from ..export import mesh as mesh_export
from ..export import motion as motion_export
from ..export import cryptomatte as crypto_export
from ..export import world as world_export
from ..export import export_scene, light_group_indices, requested_aovs
from .frame import FrameRect, flatten_passes

LOG_PREFIX = "Deferred"


# (level, message) of recent reports, newest last: lets tests and scripts see
# warnings that Blender only prints. Bounded, so long sessions do not grow.
last_messages = collections.deque(maxlen=256)
# The native timings of the last render (stage times, programs compiled or
# loaded from the disk cache): what the status line shows, for scripts.
last_timings = {}
# The GPU of the last render: GL renderer, how the EGL device was chosen
# (device_selection.h) and a fallback note, for the log and for farm scripts
# that record which GPU rendered each frame (scripts/cluster/).
last_device = {}


class RenderCancelled(Exception):
    pass


class RenderSettingsError(RuntimeError):
    """The renderer refused the frame settings (e.g. resolution beyond the GPU)."""


def _settings(scene):
    settings = getattr(scene, "deferred_render", None)
    samples = int(getattr(settings, "samples", 16)) if settings is not None else 16
    device_index = int(getattr(settings, "device_index", -1)) if settings is not None else -1
    return max(1, samples), device_index


def _filter_width(scene):
    """Pixel filter width as Cycles reads it (scene.cycles.filter_width; the
    render.filter_size Blender shows is EEVEE's), so both engines filter the
    same way; render.filter_size without the Cycles add-on."""
    cycles = getattr(scene, "cycles", None)
    width = getattr(cycles, "filter_width", None) if cycles is not None else None
    return float(width if width is not None else scene.render.filter_size)


def _filter_splat(scene):
    """Whether the film splats each sample into its neighbours (native
    RenderSettings.filter_splat; on unless the setting turns it off)."""
    settings = getattr(scene, "deferred_render", None)
    return bool(getattr(settings, "filter_splat", True)) if settings is not None else True


def _visibility_buffer(scene):
    """Whether the G-buffer comes from the visibility buffer (native
    RenderSettings.visibility_buffer; on unless the setting turns it off)."""
    settings = getattr(scene, "deferred_render", None)
    return bool(getattr(settings, "visibility_buffer", True)) if settings is not None else True


def _light_settings(scene):
    """Culling switch and threshold (the threshold is relative to what the
    view shows, so a brighter exposure lowers it: radiance x 2^exposure),
    light samples, emission samples, shadow settings."""
    settings = getattr(scene, "deferred_render", None)
    culling = bool(getattr(settings, "light_culling", True)) if settings is not None else True
    threshold = float(getattr(settings, "light_threshold", 1e-3)) if settings is not None else 1e-3
    exposure = float(getattr(scene.view_settings, "exposure", 0.0))
    shadow_resolution = int(getattr(settings, "shadow_resolution", 1024)) if settings is not None else 1024
    shadow_quality = float(getattr(settings, "shadow_quality", 1.0)) if settings is not None else 1.0
    shadow_rays = settings is not None and getattr(settings, "shadow_method", "MAPS") == "RAYS"
    light_samples = int(getattr(settings, "light_samples", 16)) if settings is not None else 16
    emission_samples = int(getattr(settings, "emission_samples", 0)) if settings is not None else 0
    return {"light_culling": culling, "light_threshold": threshold / (2.0 ** exposure), "light_samples": light_samples,
            "emission_samples": emission_samples,
            "shadow_resolution": shadow_resolution, "shadow_quality": shadow_quality,
            "shadow_rays": shadow_rays}


def _alpha_threshold(view_layer):
    """The view layer's Alpha Threshold in [0, 1] (Blender's default 0.5 if not finite)."""
    value = float(getattr(view_layer, "pass_alpha_threshold", 0.5))
    return min(max(value, 0.0), 1.0) if math.isfinite(value) else 0.5


def _format_timings(timings):
    if not timings:
        return ""
    parts = [f"{k.replace('_ms', '')} {v:.1f}" for k, v in timings.items()
             if isinstance(v, (int, float)) and k.endswith("_ms") and k != "total_ms"]
    total = timings.get("total_ms")
    text = ", ".join(parts)
    if total is not None:
        text = f"{total:.1f} ms ({text})" if text else f"{total:.1f} ms"
    compiled, loaded = timings.get("programs_compiled", 0), timings.get("programs_loaded", 0)
    if compiled or loaded:
        text += f"; programs {compiled} compiled, {loaded} from the cache"
    uploaded, reused = timings.get("images_uploaded", 0), timings.get("images_reused", 0)
    if uploaded or reused:
        text += f"; images {uploaded} uploaded, {reused} kept from the last render"
    layers = timings.get("exact_layers", 0)
    if layers:
        text += f"; {layers} transparent surfaces composited exactly"
    return text


def _is_user_facing(ex):
    """Errors whose message says all (bad scene, missing module, GPU limits)."""
    if isinstance(ex, (native.NativeUnavailable, camera_export.CameraError, RenderSettingsError)):
        return True
    mod = native.try_load()
    error_type = getattr(mod, "Error", None) if mod is not None else None
    return error_type is not None and isinstance(ex, error_type) and not isinstance(ex, ValueError)


class FinalRender:
    """State of one render() call; created and dropped by the engine."""

    def __init__(self, engine, depsgraph):
        self.reused_renderer = False
        self.engine = engine
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene
        self.view_layer = depsgraph.view_layer
        self.gl_name = "?"
        self.t0 = time.perf_counter()

    # -- status bar -------------------------------------------------------
    def status(self, text, progress=None):
        self.engine.update_stats("", f"{LOG_PREFIX} | {self.gl_name} | {self.view_layer.name} | {text}")
        if progress is not None:
            self.engine.update_progress(progress)

    def report(self, level, message):
        text = f"{LOG_PREFIX}: {message}"
        last_messages.append((level, text))
        self.engine.report({level}, text)

    def warn(self, message):
        self.report('WARNING', message)

    def check_break(self):
        if self.engine.test_break():
            raise RenderCancelled()

    # -- the render -------------------------------------------------------
    def run(self):
        try:
            self._run()
        except Exception as ex:  # last resort: nothing may propagate into Blender
            self.report('ERROR', str(ex) or type(ex).__name__)
            traceback.print_exc()

    def _run(self):
        engine = self.engine
        scene = self.scene
        frame = FrameRect.from_render_settings(scene.render, engine.resolution_x, engine.resolution_y)
        if frame.width <= 0 or frame.height <= 0:
            self.report('ERROR', f"empty render region {frame}")
            return
        result = engine.begin_result(0, 0, frame.width, frame.height, layer=self.view_layer.name)
        if result is None:
            self.report('ERROR', f"Blender gave no render result for view layer "
                                 f"'{self.view_layer.name}' ({frame})")
            return
        frame.fit_to_result(result.resolution_x, result.resolution_y)
        renderer = None
        cancelled = False
        self._session = None
        try:
            renderer = self._render_into(result, frame)
        except RenderCancelled:
            cancelled = True
        except Exception as ex:  # every failure is reported, never raised into Blender
            message = str(ex) or type(ex).__name__
            self.report('ERROR', message)
            if not _is_user_facing(ex):
                # An unexpected failure (a bug): keep the traceback for the log.
                print(f"{LOG_PREFIX}: render failed:", file=sys.stderr)
                traceback.print_exc()
            try:
                engine.error_set(f"{LOG_PREFIX}: {message}")
            except Exception:
                pass
            self.status(f"Error: {message}")
        finally:
            if getattr(self, "_restore_frame", None) is not None:  # failed between motion and export
                try:
                    motion_export.restore(engine, *self._restore_frame)
                except Exception:
                    pass
                self._restore_frame = None
            # Keep the native session for the next render (its data too with
            # Persistent Data) or, after a failure, release it (joins its GL
            # thread, frees the GL context) before handing the result back.
            if self._session is not None:
                mod, device_index, persistent = self._session
                session.hand_back(mod, device_index, renderer, persistent, failed=renderer is None)
            renderer = None  # noqa: F841
            engine.end_result(result, cancel=cancelled)

    def _write_capture(self, recorder, path, renderer, t_export, t_render):
        """The calls of this render to ``path`` (capture.py); a failure to
        write is reported, the render itself stands."""
        if recorder.error:
            self.warn(f"scene not captured to '{path}': {recorder.error}")
            return
        try:
            import bpy
            meta = {"blender": bpy.app.version_string, "file": bpy.data.filepath, "scene": self.scene.name,
                    "view_layer": self.view_layer.name, "frame": self.scene.frame_current,
                    "gl_renderer": self.gl_name, "export_s": t_export, "render_s": t_render,
                    "timings": {k: v for k, v in dict(renderer.last_timings).items()
                                if isinstance(v, (int, float, bool))}}
            recorder.write(path, meta)
            self.report('INFO', f"scene captured to {path} ({len(recorder.calls)} calls, {len(recorder.arrays)} arrays)")
        except Exception as ex:
            self.warn(f"scene capture to '{path}' failed: {ex}")

    def _log_device(self, renderer):
        """Names the GPU in the status line and, once per new renderer, in the log."""
        try:
            info = dict(renderer.gl_info)
        except Exception:
            info = {}
        self.gl_name = info.get("renderer", "?")
        last_device.clear()
        last_device.update(gpu=self.gl_name, display=info.get("display", ""),
                           note=info.get("device_note", ""))
        if not self.reused_renderer:
            print(f"{LOG_PREFIX}: rendering on {self.gl_name} ({last_device['display']})", flush=True)
            if last_device["note"]:
                print(f"{LOG_PREFIX}: device note: {last_device['note']}", flush=True)
            if info.get("allocator_note"):
                print(f"{LOG_PREFIX}: note: {info['allocator_note']}", flush=True)

    def _render_cancellable(self, renderer, mod, camera, frame, kwargs):
        """The native render on a worker thread (it releases the GIL and
        touches no bpy data), while this thread polls test_break() and asks
        the renderer to stop at its next sample when the user cancels."""
        outcome = {}

        def work():
            try:
                outcome["images"] = renderer.render(camera, frame.full_width, frame.full_height, **kwargs)
            except BaseException as ex:  # re-raised on the main thread
                outcome["error"] = ex

        worker = threading.Thread(target=work, name="deferred-render", daemon=True)
        worker.start()
        while worker.is_alive():
            worker.join(0.05)
            if worker.is_alive() and self.engine.test_break():
                renderer.cancel()
                worker.join()
        if "error" in outcome:
            cancelled_type = getattr(mod, "Cancelled", None)
            if cancelled_type is not None and isinstance(outcome["error"], cancelled_type):
                raise RenderCancelled()
            raise outcome["error"]
        return outcome["images"]

    def _render_into(self, result, frame):
        engine = self.engine
        scene = self.scene
        samples, device_index = _settings(scene)

        self.status("loading the native renderer", 0.0)
        mod = native.load()
        self.check_break()

        # Resolve the camera before starting the GL context: a scene without
        # camera fails fast with a clear message.
        camera_object = engine.camera_override or scene.camera
        if camera_object is not None:
            camera_object = camera_object.original.evaluated_get(self.depsgraph)
        cam_params, cam_warnings = camera_export.camera_params(scene, camera_object, engine)
        for message in cam_warnings:
            self.warn(message)

        layer = result.layers[0]
        pass_names = []
        for render_pass in layer.passes:
            if render_pass.name not in pass_names:
                pass_names.append(render_pass.name)
        # Motion Blur, or the Vector pass: the scene at other times
        # (motion.py), collected before this frame's export, which reads the
        # depsgraph at the middle step it is left at.
        self._motion_blur = bool(getattr(scene.render, "use_motion_blur", False))
        self._restore_frame = None
        motion = None
        if self._motion_blur:
            shutter, middle_delta = motion_export.blur_settings(scene)
            for message in motion_export.blur_warnings(self.depsgraph):
                self.warn(message)
            if "Vector" in pass_names:
                self.warn("the Vector pass is empty with Motion Blur on, as in Cycles")
            self.status("evaluating the shutter's open and close (Motion Blur)", 0.01)
            if middle_delta != 0.0:
                self._restore_frame = (scene.frame_current, scene.frame_subframe)
            motion = motion_export.collect(engine, self.depsgraph, camera_object, mesh_export.MESHABLE_TYPES,
                                           half_span=0.5 * shutter, middle_delta=middle_delta)
            if middle_delta != 0.0:  # the camera at the middle of the shutter
                camera_object = camera_object.original.evaluated_get(self.depsgraph)
                cam_params, _ = camera_export.camera_params(scene, camera_object, engine)
            if motion.lens_moves(cam_params):
                self.warn("Motion Blur: the camera's lens, ortho scale or shift change over the shutter; "
                          "not blurred (the middle of the shutter's is used)")
        elif "Vector" in pass_names:
            self.status("evaluating the previous and next frames (Vector pass)", 0.01)
            motion = motion_export.collect(engine, self.depsgraph, camera_object, mesh_export.MESHABLE_TYPES)
        if motion is not None:
            camera_motion = motion.camera(cam_params["matrix"])
            if camera_motion is not None:
                cam_params["motion"] = camera_motion
            self.check_break()

        persistent = bool(getattr(scene.render, "use_persistent_data", False))
        # DEFERRED_RENDER_CAPTURE: record every call on the renderer (capture.py);
        # a fresh renderer, so the file holds every mesh and image.
        capture_to = capture.capture_path(scene.frame_current)
        recorder = capture.Recorder() if capture_to else None
        if recorder is not None:
            persistent = False
        self.status("reusing the renderer kept by the last render (Persistent Data)"
                    if persistent and session.kept() else
                    "reusing the GL context and programs of the last render" if session.renderers_held() else
                    "starting GL", 0.02)
        renderer, self.reused_renderer = session.acquire(mod, device_index, persistent)
        self._session = (mod, device_index, persistent)
        if recorder is not None:
            renderer = capture.CaptureRenderer(renderer, recorder)
        self._log_device(renderer)
        self.check_break()

        self.status("exporting scene", 0.05)
        t_export = time.perf_counter()
        try:
            stats, cancelled = export_scene(self.depsgraph, renderer, warn=self.warn,
                                            test_break=engine.test_break, motion=motion)
        finally:
            if self._restore_frame is not None:  # the middle of the shutter was not the frame
                motion_export.restore(engine, *self._restore_frame)
                self._restore_frame = None
        if cancelled:
            raise RenderCancelled()
        t_export = time.perf_counter() - t_export
        self.status(f"exported {stats.summary()} in {t_export:.2f} s", 0.3)
        self.check_break()

        produced = {entry[0] for entry in mod.PASSES}
        requested = [name for name in pass_names if name in produced]
        if "Combined" not in requested:
            requested.insert(0, "Combined")

        camera = recorder.camera(mod, **cam_params) if recorder is not None else mod.Camera(**cam_params)
        mist = world_export.mist_params(scene.world)
        self.status(f"rendering {frame.full_width}x{frame.full_height}, {samples} samples, "
                    f"{len(requested)} passes", 0.35)
        t_render = time.perf_counter()
        crypto_layers, crypto_levels = crypto_export.enabled_layers(self.view_layer)
        light_groups = light_group_indices(self.view_layer)
        kwargs = dict(passes=requested, film_transparent=bool(scene.render.film_transparent),
                      cryptomatte=crypto_layers, cryptomatte_levels=crypto_levels or 6,
                      aovs=requested_aovs(self.view_layer),
                      light_groups=len(light_groups), motion_blur=self._motion_blur,
                      samples=samples, filter_width=_filter_width(scene), filter_splat=_filter_splat(scene),
                      visibility_buffer=_visibility_buffer(scene),
                      alpha_threshold=_alpha_threshold(self.view_layer),
                      **_light_settings(scene), **mist)
        try:
            images = self._render_cancellable(renderer, mod, camera, frame, kwargs)
        except ValueError as ex:  # size/settings validation: the message says it all
            raise RenderSettingsError(str(ex)) from ex
        for name, index in light_groups.items():  # the renderer names them by index
            if f"#lightgroup{index}" in images:
                images[f"Combined_{name}"] = images.pop(f"#lightgroup{index}")
        t_render = time.perf_counter() - t_render
        if recorder is not None:
            self._write_capture(recorder, capture_to, renderer, t_export, t_render)
        for message in getattr(renderer, "last_warnings", ()):
            self.warn(message)
        self.check_break()

        self.status("writing passes", 0.9)
        flat, missing = flatten_passes(layer.passes, images, frame)
        if missing:
            self.warn("passes not produced by the renderer (left at zero): " + ", ".join(missing))
        layer.passes.foreach_set("rect", flat)
        if crypto_layers and stats.cryptomatte is not None:
            # The manifests, where the compositor's Cryptomatte node and EXR
            # readers find them: on the render's own result (get_result, as
            # Cycles' stamp_view_layer_metadata), not this tile's.
            final_result = engine.get_result()
            for key, value in stats.cryptomatte.metadata(self.view_layer.name):
                final_result.stamp_data_add_field(key, value)
        engine.update_result(result)

        try:
            last_timings.clear()
            last_timings.update(dict(renderer.last_timings))
            timings = _format_timings(dict(renderer.last_timings))
        except Exception:
            timings = ""
        total = time.perf_counter() - self.t0
        self.status(f"done in {total:.2f} s: export {t_export:.2f} s, render {t_render:.2f} s"
                    + (" (renderer kept from the last render)" if self.reused_renderer else "")
                    + (f" [{timings}]" if timings else ""), 1.0)
        return renderer


# Material / world / light preview thumbnails rendered (bl_use_preview):
# Blender's preview scenes come through render() with engine.is_preview.
preview_renders = 0


def render(engine, depsgraph):
    global preview_renders
    if engine.is_preview:
        preview_renders += 1
    FinalRender(engine, depsgraph).run()

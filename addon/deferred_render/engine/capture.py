"""Scene capture: ``DEFERRED_RENDER_CAPTURE=/path/scene.npz`` in the
environment makes every final render write the exact calls it makes on the
native renderer (the arrays, materials, lights, camera and settings, in
order) to that file, so ``build/tools/deferred_render_replay scene.npz``
renders the same frame without Blender: the benchmark on any GPU server, and
a scene a user can attach to a bug report.

``#`` characters in the path are replaced by the frame number, zero-padded
to their count, as in Blender's output path (``/tmp/shot_####.npz``);
without them each render overwrites the file. Viewport renders are not
captured.

The file is an uncompressed numpy ``.npz``: ``__calls__`` holds the calls as
JSON (uint8 bytes), ``__meta__`` what rendered them (JSON), and every numpy
array the calls pass is its own entry, referenced from the JSON as
``{"__array__": key}``. Tuples are ``{"__tuple__": [...]}`` (the bindings
tell tuples from lists), the camera ``{"__camera__": {its keyword
arguments}}``. A capturing render starts its own renderer (Persistent Data
would let it reuse meshes and images the file would then lack). The file is
written next to its final name and renamed into place: never half-written.
"""

import json
import os
import re

import numpy as np

ENV = "DEFERRED_RENDER_CAPTURE"
FORMAT = 1

# The Renderer methods that build the scene or render it, replayed in order.
RECORDED = ("clear_scene", "add_mesh", "add_image", "add_graph_material", "add_material", "add_instances",
            "add_light", "set_world", "render")


def capture_path(frame_number):
    """The file this render captures to, or None when not capturing."""
    path = os.environ.get(ENV, "").strip()
    if not path:
        return None
    return re.sub(r"#+", lambda m: str(int(frame_number)).zfill(len(m.group(0))), path)


class Recorder:
    """The calls made so far and the arrays they passed."""

    def __init__(self):
        self.calls = []
        self.arrays = {}
        self.error = None  # why a call could not be recorded: nothing is written then
        self._cameras = {}  # id(Camera) -> (Camera, its keyword arguments)

    def camera(self, mod, **params):
        """mod.Camera(**params), remembered so render(camera, ...) can be written."""
        cam = mod.Camera(**params)
        self._cameras[id(cam)] = (cam, dict(params))
        return cam

    def encode(self, value):
        if isinstance(value, np.ndarray):
            key = f"a{len(self.arrays)}"
            self.arrays[key] = np.ascontiguousarray(value)
            return {"__array__": key}
        if isinstance(value, np.generic):
            return value.item()
        if isinstance(value, tuple):
            return {"__tuple__": [self.encode(v) for v in value]}
        if isinstance(value, list):
            return [self.encode(v) for v in value]
        if isinstance(value, dict):
            if not all(isinstance(k, str) for k in value):
                raise TypeError("capture: a dict with non-string keys")
            return {"__dict__": {k: self.encode(v) for k, v in value.items()}}
        if value is None or isinstance(value, (bool, int, float, str)):
            return value
        known = self._cameras.get(id(value))
        if known is not None and known[0] is value:
            return {"__camera__": self.encode(known[1])}
        raise TypeError(f"capture: cannot record a {type(value).__name__}")

    def record(self, method, args, kwargs):
        self.calls.append({"method": method, "args": self.encode(list(args)), "kwargs": self.encode(kwargs)})

    def write(self, path, meta):
        """Writes the capture to ``path`` (renamed into place when complete)."""
        directory = os.path.dirname(os.path.abspath(path))
        os.makedirs(directory, exist_ok=True)
        entries = dict(self.arrays)
        entries["__calls__"] = np.frombuffer(json.dumps(self.calls).encode("utf-8"), dtype=np.uint8)
        entries["__meta__"] = np.frombuffer(json.dumps(dict(meta, format=FORMAT)).encode("utf-8"), dtype=np.uint8)
        temp = os.path.join(directory, "." + os.path.basename(path) + ".part")
        try:
            with open(temp, "wb") as f:  # a file object: savez adds no ".npz" to the name
                np.savez(f, **entries)
            os.replace(temp, path)
        finally:
            if os.path.exists(temp):
                os.remove(temp)


class CaptureRenderer:
    """A native Renderer that records its scene-building and render calls;
    everything else passes through."""

    def __init__(self, renderer, recorder):
        self._renderer = renderer
        self._recorder = recorder

    def __getattr__(self, name):
        attr = getattr(self._renderer, name)
        if name not in RECORDED:
            return attr

        def call(*args, **kwargs):
            # Recorded once it succeeded: a call the exporter sees fail (and
            # skips, warned) is not in the file, so the replay does not fail on it.
            result = attr(*args, **kwargs)
            try:  # a capture never fails the render: a call it cannot record only voids the file
                self._recorder.record(name, args, kwargs)
            except Exception as ex:
                self._recorder.error = self._recorder.error or f"{name}: {ex}"
            return result

        return call

    @property
    def unwrapped(self):
        return self._renderer

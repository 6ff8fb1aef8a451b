"""The native renderer kept between renders: Render Properties > Performance >
Final Render > Persistent Data (``scene.render.use_persistent_data``), the
option Blender users know from Cycles, with the same meaning: keep render
data for faster re-renders and animation frames, at the cost of GPU memory
held between renders.

With it on, a render hands its renderer back here instead of releasing it,
and the next render (the next frame of ``blender -b -a``, F12 again) takes it
back: the GL context, the compiled programs and the frame targets are
reused, and images are found by their content key instead of uploaded
again (``Renderer.find_image``). The scene itself is exported again in full
(incremental updates are the viewport's and the GPU issue's work).

With it off (Blender's default), each render starts a renderer and releases
it at the end, and any renderer kept earlier is released first, so turning
the option off gives the memory back on the next render.

One renderer is kept at most, for one device. A render that fails drops its
renderer (its GL state is not trusted); a render running while another holds
the kept one starts its own. The add-on's unregister and a file load release
the kept renderer (``release()``).
"""

import threading

_lock = threading.Lock()
_kept = None  # (native module, device index, Renderer)


def acquire(mod, device_index, persistent):
    """(renderer, reused): the kept renderer when ``persistent`` and it
    matches the module and device (export_scene clears its scene), else a
    new one."""
    global _kept
    with _lock:
        kept, _kept = _kept, None
    if kept is not None:
        kept_mod, kept_device, renderer = kept
        if persistent and kept_mod is mod and kept_device == device_index:
            return renderer, True
        del renderer
        kept = None
    return mod.Renderer(device_index=device_index), False


def hand_back(mod, device_index, renderer, persistent, failed=False):
    """Keep ``renderer`` for the next render when ``persistent`` and the
    render did not fail; otherwise let it go (the caller drops its reference)."""
    global _kept
    if not persistent or failed or renderer is None:
        return
    with _lock:
        if _kept is None:
            _kept = (mod, device_index, renderer)


def kept():
    """True if a renderer is kept now."""
    with _lock:
        return _kept is not None


def release():
    """Release the kept renderer (joins its GL thread, frees its GPU memory)."""
    global _kept
    with _lock:
        kept, _kept = _kept, None
    del kept

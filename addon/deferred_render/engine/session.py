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

With it off (Blender's default), a render releases its scene, images, frame
targets and shadow maps at its end (``Renderer.release_scene_memory``) and
keeps only the GL context and its compiled programs for the next render,
as Blender keeps EEVEE's shaders and Cycles its kernels: starting a context
and linking the programs again (from the disk cache, and llvmpipe's
compilation of them at their first draws) cost ~0.1–0.2 s a render on
llvmpipe. A renderer kept with its data when the option is turned off
releases it at the next render's start, so turning the option off gives
the memory back then.

One renderer is kept at most, for one device. A render that fails drops its
renderer (its GL state is not trusted); a render running while another holds
the kept one starts its own. The add-on's unregister and a file load release
the kept renderer (``release()``).
"""

import threading

_lock = threading.Lock()
_kept = None  # (native module, device index, Renderer, whether it holds the last render's data)


def acquire(mod, device_index, persistent):
    """(renderer, reused): the kept renderer when it matches the module and
    device (export_scene clears its scene), else a new one; ``reused`` when
    it still holds the last render's data and ``persistent`` keeps it. Not
    ``persistent``: a renderer kept with its data releases it first."""
    global _kept
    with _lock:
        kept, _kept = _kept, None
    if kept is not None:
        kept_mod, kept_device, renderer, holds_data = kept
        kept = None
        if kept_mod is mod and kept_device == device_index:
            try:
                if holds_data and not persistent:
                    renderer.release_scene_memory()
                return renderer, holds_data and persistent
            except Exception:  # its GL state is not trusted: a new one below
                pass
        del renderer
    return mod.Renderer(device_index=device_index), False


def hand_back(mod, device_index, renderer, persistent, failed=False):
    """Keep ``renderer`` for the next render unless the render failed: with
    its data when ``persistent``, else with its context and programs only
    (its scene memory released now). The caller drops its reference."""
    global _kept
    if failed or renderer is None:
        return
    if not persistent:
        try:
            renderer.release_scene_memory()
        except Exception:  # its GL state is not trusted: let it go
            return
    with _lock:
        if _kept is None:
            _kept = (mod, device_index, renderer, bool(persistent))


def kept():
    """True if a renderer is kept with the last render's data (Persistent Data)."""
    with _lock:
        return _kept is not None and _kept[3]


def renderers_held():
    """Native renderers this module holds (0 or 1): the one kept, with its
    data or with its context and programs only."""
    with _lock:
        return 0 if _kept is None else 1


def release():
    """Release the kept renderer (joins its GL thread, frees its GPU memory)."""
    global _kept
    with _lock:
        kept, _kept = _kept, None
    del kept

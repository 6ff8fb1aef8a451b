"""Lazy, guarded import of the compiled module ``deferred_native``.

The module is built by the root CMake into
``build/blender_scripts/addons/deferred_render/`` next to a copy of this
package. Nothing imports it at registration time: the engine registers even
when the module is missing or broken (wrong Python, missing shared library),
and render() turns the failure into one clear error message.

The outcome of the first import attempt is kept for the Blender session (like
any add-on, a rebuilt module needs a Blender restart).
"""

import importlib

_MODULE_NAME = "deferred_native"

_module = None
_error = None


class NativeUnavailable(RuntimeError):
    """The compiled renderer could not be imported."""


def load():
    """Return the ``deferred_native`` module or raise NativeUnavailable."""
    global _module, _error
    if _module is not None:
        return _module
    if _error is None:
        try:
            _module = importlib.import_module("." + _MODULE_NAME, __package__)
            return _module
        except Exception as ex:  # ImportError, OSError from the loader, anything in init
            _error = (
                f"the native renderer module '{_MODULE_NAME}' could not be imported "
                f"({type(ex).__name__}: {ex}). Build it with "
                "'cmake -S . -B build && cmake --build build' and start Blender with "
                "BLENDER_USER_SCRIPTS=<repo>/build/blender_scripts, or install the "
                "built add-on zip"
            )
    raise NativeUnavailable(_error)


def try_load():
    """The module, or None if it cannot be imported (no exception)."""
    try:
        return load()
    except NativeUnavailable:
        return None


def error_message():
    """Why the import failed, or None."""
    try_load()
    return _error

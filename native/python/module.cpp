// Python module `deferred_native`: the thin layer between the Blender add-on
// and the native renderer.
#include "bindings.h"

PYBIND11_MODULE(deferred_native, m) {
    m.doc() = "Native headless deferred renderer (EGL + OpenGL 4.5) for the Blender add-on";
    deferred::python::declare_scene(m);
    deferred::python::declare_renderer(m);
    deferred::python::declare_geometry(m);
}

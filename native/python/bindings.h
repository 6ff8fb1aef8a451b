// One binding file per area (OpenImageIO/Open3D style); module.cpp calls them.
#pragma once

#include <deferred/renderer.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace deferred::python {

namespace py = pybind11;

void declare_scene(py::module_& m);     // Camera, PASSES, exceptions
void declare_renderer(py::module_& m);  // Renderer

// Row-major (4,4) float64 numpy matrix (as np.array(blender_matrix) gives) ->
// the library's column-major Mat4d. Raises ValueError naming `what`.
Mat4d matrix_from_python(const py::handle& obj, const char* what);

}  // namespace deferred::python

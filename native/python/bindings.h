// One binding file per area (OpenImageIO/Open3D style); module.cpp calls them.
#pragma once

#include <deferred/renderer.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <initializer_list>
#include <string>

namespace deferred::python {

namespace py = pybind11;

void declare_scene(py::module_& m);     // Camera, PASSES, exceptions
void declare_renderer(py::module_& m);  // Renderer
void declare_geometry(py::module_& m);  // compute_tangents, compute_pointiness, compute_random_per_island

// Row-major (4,4) float64 numpy matrix (as np.array(blender_matrix) gives) ->
// the library's column-major Mat4d. Raises ValueError naming `what`.
Mat4d matrix_from_python(const py::handle& obj, const char* what);

// Checks dtype, C-contiguity and shape of a numpy array without copying it
// (the renderer uploads before returning, so borrowing the buffer is safe).
// `shape` uses -1 for "any"; returns the array's data pointer.
template <class T>
inline const T* borrow(const py::handle& obj, const char* name, std::initializer_list<py::ssize_t> shape,
                py::ssize_t* first_dim = nullptr) {
    if (!py::isinstance<py::array>(obj))
        throw py::value_error(std::string(name) + ": expected a numpy array, got " +
                              std::string(py::str(py::type::of(obj).attr("__name__"))));
    py::array a = py::reinterpret_borrow<py::array>(obj);
    // equal(), not is(): a dtype that came through pickle is an equal, distinct object.
    if (!a.dtype().equal(py::dtype::of<T>()))
        throw py::value_error(std::string(name) + ": expected dtype " + std::string(py::str(py::dtype::of<T>())) +
                              ", got " + std::string(py::str(a.dtype())));
    if (!(a.flags() & py::array::c_style))
        throw py::value_error(std::string(name) + ": array must be C-contiguous (use numpy.ascontiguousarray)");
    if (a.ndim() != py::ssize_t(shape.size())) {
        std::string want = "(";
        for (auto s : shape) want += (s < 0 ? std::string("N") : std::to_string(s)) + ",";
        want.back() = ')';
        throw py::value_error(std::string(name) + ": expected shape " + want + ", got " + std::to_string(a.ndim()) +
                              " dimension(s)");
    }
    int i = 0;
    for (auto s : shape) {
        if (s >= 0 && a.shape(i) != s)
            throw py::value_error(std::string(name) + ": dimension " + std::to_string(i) + " must be " +
                                  std::to_string(s) + ", got " + std::to_string(a.shape(i)));
        ++i;
    }
    if (first_dim) *first_dim = a.ndim() > 0 ? a.shape(0) : 0;
    return static_cast<const T*>(a.data());
}

}  // namespace deferred::python

#include "bindings.h"

#include <pybind11/stl.h>

#include <cmath>
#include <string>

namespace deferred::python {

Mat4d matrix_from_python(const py::handle& obj, const char* what) {
    py::array_t<double, py::array::c_style | py::array::forcecast> a;
    try {
        a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
    } catch (const py::error_already_set&) {
    }
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
        throw py::value_error(std::string(what) + ": expected a (4, 4) matrix");
    Mat4d m;
    auto r = a.unchecked<2>();
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) {
            const double v = r(row, col);
            if (!std::isfinite(v)) throw py::value_error(std::string(what) + ": matrix has NaN/Inf");
            m[std::size_t(col * 4 + row)] = v;
        }
    return m;
}

namespace {

template <class Enum>
Enum enum_from_name(const std::string& value, std::initializer_list<std::pair<const char*, Enum>> names,
                    const char* what) {
    std::string allowed;
    for (auto& [n, e] : names) {
        if (value == n) return e;
        allowed += std::string(allowed.empty() ? "" : ", ") + n;
    }
    throw py::value_error(std::string(what) + ": '" + value + "' is not one of " + allowed);
}

}  // namespace

void declare_scene(py::module_& m) {
    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    static py::exception<Cancelled> cancelled(m, "Cancelled", error.ptr());
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InvalidInput& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const Cancelled& e) {
            cancelled(e.what());
        } catch (const Error& e) {
            error(e.what());
        }
    });

    py::list passes;
    for (std::uint32_t i = 0; i < kPassCount; ++i) {
        const PassInfo& p = pass_info(Pass(i));
        passes.append(py::make_tuple(p.name, p.chan_id, p.channels));
    }
    m.attr("PASSES") = passes;

    py::class_<Camera>(m, "Camera", "Blender camera parameters (matrix: row-major 4x4 world matrix)")
        .def(py::init([](const std::string& type, const py::object& matrix, float lens, float sensor_width,
                         float sensor_height, const std::string& sensor_fit, float shift_x, float shift_y,
                         float clip_start, float clip_end, float ortho_scale, float pixel_aspect_x,
                         float pixel_aspect_y, const py::object& fov, const py::object& viewplane,
                         const py::object& motion) {
                 Camera c;
                 c.type = enum_from_name<CameraType>(
                     type, {{"PERSP", CameraType::Perspective}, {"ORTHO", CameraType::Orthographic}}, "Camera.type");
                 if (!matrix.is_none()) c.matrix = matrix_from_python(matrix, "Camera.matrix");
                 c.lens = lens;
                 c.sensor_width = sensor_width;
                 c.sensor_height = sensor_height;
                 c.sensor_fit = enum_from_name<SensorFit>(sensor_fit,
                                                          {{"AUTO", SensorFit::Auto},
                                                           {"HORIZONTAL", SensorFit::Horizontal},
                                                           {"VERTICAL", SensorFit::Vertical}},
                                                          "Camera.sensor_fit");
                 c.shift_x = shift_x;
                 c.shift_y = shift_y;
                 c.clip_start = clip_start;
                 c.clip_end = clip_end;
                 c.ortho_scale = ortho_scale;
                 c.pixel_aspect_x = pixel_aspect_x;
                 c.pixel_aspect_y = pixel_aspect_y;
                 if (!fov.is_none()) {
                     // Blender's Camera.fov: 2 atan(sensor / (2 lens)), with the
                     // sensor dimension chosen by sensor_fit (AUTO: width).
                     const double f = fov.cast<double>();
                     if (!(f > 0.0 && f < M_PI)) throw py::value_error("Camera.fov must be in (0, pi) radians");
                     const double sensor = c.sensor_fit == SensorFit::Vertical ? c.sensor_height : c.sensor_width;
                     c.lens = float(0.5 * sensor / std::tan(0.5 * f));
                 }
                 if (!viewplane.is_none()) {
                     const auto v = viewplane.cast<std::vector<float>>();
                     if (v.size() != 4) throw py::value_error("Camera.viewplane: expected (left, right, bottom, top)");
                     if (!(v[1] > v[0] && v[3] > v[2]))
                         throw py::value_error("Camera.viewplane: needs left < right and bottom < top");
                     std::copy(v.begin(), v.end(), c.viewplane.begin());
                 }
                 if (!motion.is_none()) {
                     // (previous, next) world matrices, as `matrix`.
                     const py::tuple t = motion.cast<py::tuple>();
                     if (t.size() != 2) throw py::value_error("Camera.motion: expected (previous, next) matrices");
                     c.matrix_previous = matrix_from_python(t[0], "Camera.motion[0]");
                     c.matrix_next = matrix_from_python(t[1], "Camera.motion[1]");
                     c.has_motion = true;
                 }
                 return c;
             }),
             py::kw_only(), py::arg("type") = "PERSP", py::arg("matrix") = py::none(), py::arg("lens") = 50.0f,
             py::arg("sensor_width") = 36.0f, py::arg("sensor_height") = 24.0f, py::arg("sensor_fit") = "AUTO",
             py::arg("shift_x") = 0.0f, py::arg("shift_y") = 0.0f, py::arg("clip_start") = 0.1f,
             py::arg("clip_end") = 100.0f, py::arg("ortho_scale") = 6.0f, py::arg("pixel_aspect_x") = 1.0f,
             py::arg("pixel_aspect_y") = 1.0f, py::arg("fov") = py::none(),
             py::arg("viewplane") = py::none(), py::arg("motion") = py::none())
        .def_readwrite("lens", &Camera::lens)
        .def_readwrite("clip_start", &Camera::clip_start)
        .def_readwrite("clip_end", &Camera::clip_end);
}

}  // namespace deferred::python

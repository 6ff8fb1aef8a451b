#include "bindings.h"

#include <pybind11/stl.h>

#include <memory>
#include <string>

namespace deferred::python {

namespace {

Vec3 vec3_from(const py::handle& obj, const char* what) {
    // Any sequence of at least 3 numbers (tuple, list, numpy array, mathutils
    // Color; RGBA gives its RGB); everything else is a ValueError naming the argument.
    const bool sequence = PySequence_Check(obj.ptr()) && !py::isinstance<py::str>(obj) && !py::isinstance<py::bytes>(obj);
    if (!sequence || py::len(obj) < 3)
        throw py::value_error(std::string(what) + ": expected 3 numbers (RGB), got " +
                              std::string(py::str(py::repr(obj))).substr(0, 60));
    py::sequence s = py::reinterpret_borrow<py::sequence>(obj);
    Vec3 v;
    for (std::size_t i = 0; i < 3; ++i) {
        PyObject* f = PyNumber_Float(s[i].ptr());
        if (!f) {
            PyErr_Clear();
            throw py::value_error(std::string(what) + ": element " + std::to_string(i) + " is not a number");
        }
        v[i] = float(PyFloat_AsDouble(f));
        Py_DECREF(f);
    }
    return v;
}

// A Python int in [0, 2^32) (ids, slots, pass indices): ValueError otherwise.
std::uint32_t index_from(const py::handle& obj, const std::string& what) {
    if (!PyIndex_Check(obj.ptr()) || py::isinstance<py::bool_>(obj))
        throw py::value_error(what + ": expected an integer, got " + std::string(py::str(py::type::of(obj).attr("__name__"))));
    const long long v = PyLong_AsLongLong(py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr())).ptr());
    if (PyErr_Occurred()) {
        PyErr_Clear();
        throw py::value_error(what + ": integer out of range");
    }
    if (v < 0 || v > 0xffffffffLL) throw py::value_error(what + ": " + std::to_string(v) + " is out of range");
    return std::uint32_t(v);
}

SocketType socket_type_from(const py::handle& obj, const std::string& what) {
    const std::string t = py::str(obj);
    if (t == "float") return SocketType::Float;
    if (t == "color") return SocketType::Color;
    if (t == "vector") return SocketType::Vector;
    if (t == "closure") return SocketType::Closure;
    throw py::value_error(what + ": type '" + t + "' is not one of float, color, vector, closure");
}

int int_from(const py::handle& obj, const std::string& what) {
    if (!PyIndex_Check(obj.ptr()) || py::isinstance<py::bool_>(obj))
        throw py::value_error(what + ": expected an integer");
    const long long v = PyLong_AsLongLong(py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr())).ptr());
    if (PyErr_Occurred() || v < -(1LL << 30) || v > (1LL << 30)) {
        PyErr_Clear();
        throw py::value_error(what + ": integer out of range");
    }
    return int(v);
}

// The add-on's graph dict (materials/builder.py) -> MaterialGraph. Shapes
// and kinds are checked here; links, offsets and names by the renderer.
MaterialGraph graph_from_python(const py::dict& d) {
    MaterialGraph g;
    if (d.contains("name")) g.name = d["name"].cast<std::string>();
    if (d.contains("alpha")) g.alpha = d["alpha"].cast<bool>();
    if (d.contains("closure_normal")) g.closure_normal = d["closure_normal"].cast<bool>();
    if (d.contains("aovs")) g.aovs = d["aovs"].cast<std::vector<std::string>>();
    const py::list nodes = d["nodes"].cast<py::list>();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const py::dict n = nodes[i].cast<py::dict>();
        const std::string where = "graph node " + std::to_string(i);
        GraphNode node;
        node.func = n["func"].cast<std::string>();
        for (const py::handle& a : n["args"].cast<py::list>()) {
            const py::tuple t = py::reinterpret_borrow<py::object>(a).cast<py::tuple>();
            const std::string kind = t[0].cast<std::string>();
            GraphArg arg;
            if (kind == "int" && t.size() == 2) {
                arg.kind = GraphArg::Kind::Int;
                arg.value = int_from(t[1], where);
            } else if (kind == "const" && t.size() == 3) {
                arg.kind = GraphArg::Kind::Const;
                arg.type = socket_type_from(t[1], where);
                arg.value = int_from(t[2], where);
            } else if (kind == "block" && t.size() == 3) {
                arg.kind = GraphArg::Kind::Block;
                arg.value = int_from(t[1], where);
                arg.output = int_from(t[2], where);  // length
            } else if (kind == "link" && t.size() == 5) {
                arg.kind = GraphArg::Kind::Link;
                arg.type = socket_type_from(t[1], where);
                arg.node = int_from(t[2], where);
                arg.output = int_from(t[3], where);
                arg.from = socket_type_from(t[4], where);
            } else if (kind == "shading" && t.size() == 2) {
                arg.kind = GraphArg::Kind::Shading;
                arg.name = t[1].cast<std::string>();
            } else if (kind == "image" && t.size() == 2) {
                arg.kind = GraphArg::Kind::Image;
                arg.value = int_from(t[1], where);
            } else {
                throw py::value_error(where + ": unknown argument " + std::string(py::str(py::repr(t))).substr(0, 80));
            }
            node.args.push_back(std::move(arg));
        }
        for (const py::handle& o : n["outputs"].cast<py::list>()) node.outputs.push_back(socket_type_from(o, where));
        g.nodes.push_back(std::move(node));
    }
    if (d.contains("surface") && !d["surface"].is_none()) {
        const py::tuple s = d["surface"].cast<py::tuple>();
        g.surface_node = int_from(s[0], "graph surface");
        g.surface_output = int_from(s[1], "graph surface");
    }
    if (d.contains("constants"))
        for (const py::handle& c : d["constants"]) g.constants.push_back(c.cast<float>());
    if (d.contains("images"))
        for (const py::handle& im : d["images"]) g.images.push_back(index_from(im, "graph images"));
    if (d.contains("attributes"))
        for (const py::handle& a : d["attributes"]) g.attributes.push_back(a.cast<std::string>());
    return g;
}

// Hands a pass to Python without copying: the numpy array owns the vector.
py::array_t<float> to_numpy(PassImage&& img) {
    auto* owned = new std::vector<float>(std::move(img.pixels));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>({py::ssize_t(img.height), py::ssize_t(img.width), py::ssize_t(img.channels)},
                              owned->data(), free_when_done);
}

struct PyRenderer {
    std::unique_ptr<Renderer> renderer;
    FrameTimings last;
    std::vector<std::string> last_warnings;
    Renderer& get() {
        if (!renderer) throw Error("the renderer was closed");
        return *renderer;
    }
};

}  // namespace

void declare_renderer(py::module_& m) {
    m.def("live_renderers", &Renderer::live_count,
          "Renderers alive in this process (each holds a GL context and a render thread).");
    py::class_<PyRenderer>(m, "Renderer",
                           "Headless deferred renderer; owns an EGL context on a render thread of its own.")
        .def(py::init([](int device_index) {
                 ContextOptions o;
                 o.device_index = device_index;
                 std::unique_ptr<Renderer> r;
                 {
                     py::gil_scoped_release release;
                     r = std::make_unique<Renderer>(o);
                 }
                 return PyRenderer{std::move(r), {}, {}};
             }),
             py::arg("device_index") = -1)
        .def("close", [](PyRenderer& self) {
            py::gil_scoped_release release;
            self.renderer.reset();
        }, "Release the GL context and every GPU resource now.")
        .def_property_readonly("gl_info", [](PyRenderer& self) {
            const GLInfo& i = self.get().gl_info();
            py::dict d;
            d["vendor"] = i.vendor;
            d["renderer"] = i.renderer;
            d["version"] = i.version;
            d["display"] = i.display;
            d["device_note"] = i.device_note;
            d["allocator_note"] = i.allocator_note;
            return d;
        })
        .def_property_readonly("last_timings", [](PyRenderer& self) {
            py::dict d;
            d["upload_ms"] = self.last.upload_ms;
            d["geometry_ms"] = self.last.geometry_ms;
            d["shadow_ms"] = self.last.shadow_ms;
            d["culling_ms"] = self.last.culling_ms;
            d["lighting_ms"] = self.last.lighting_ms;
            d["forward_ms"] = self.last.forward_ms;
            d["forward_batches"] = self.last.forward_batches;
            d["exact_layers"] = self.last.exact_layers;
            d["tile_light_pairs"] = self.last.tile_light_pairs;
            d["shadowed_lights"] = self.last.shadowed_lights;
            d["shadow_lights_dropped"] = self.last.shadow_lights_dropped;
            d["shadow_rays"] = self.last.shadow_rays;
            d["visibility_buffer"] = self.last.visibility_buffer;
            d["ray_build_ms"] = self.last.ray_build_ms;
            d["ray_scene_bytes"] = self.last.ray_scene_bytes;
            d["ray_triangles"] = self.last.ray_triangles;
            d["shadow_map_bytes"] = self.last.shadow_map_bytes;
            d["shadow_layers_rendered"] = self.last.shadow_layers_rendered;
            d["shadow_texels_rendered"] = self.last.shadow_texels_rendered;
            d["shadow_fragments"] = self.last.shadow_fragments;
            d["shadow_instances_drawn"] = self.last.shadow_instances_drawn;
            d["shadow_instances_one_sided"] = self.last.shadow_instances_one_sided;
            d["camera_instances_drawn"] = self.last.camera_instances_drawn;
            d["emission_samples"] = self.last.emission_samples;
            d["lighting_later_pixels"] = self.last.lighting_later_pixels;
            d["shadow_resolutions"] = self.last.shadow_resolutions;
            d["passes_ms"] = self.last.passes_ms;
            d["readback_ms"] = self.last.readback_ms;
            d["total_ms"] = self.last.total_ms;
            d["gbuffer_bytes"] = self.last.gbuffer_bytes;
            d["programs_compiled"] = self.last.programs_compiled;
            d["compile_ms"] = self.last.compile_ms;
            d["programs_loaded"] = self.last.programs_loaded;
            d["load_ms"] = self.last.load_ms;
            d["material_programs"] = self.last.material_programs;
            d["images_uploaded"] = self.last.images_uploaded;
            d["images_reused"] = self.last.images_reused;
            d["meshes_uploaded"] = self.last.meshes_uploaded;
            d["meshes_reused"] = self.last.meshes_reused;
            d["world_bake_ms"] = self.last.world_bake_ms;
            d["world_map_width"] = self.last.world_map_width;
            d["emitter_triangles"] = self.last.emitter_triangles;
            d["emission_bake_ms"] = self.last.emission_bake_ms;
            d["emission_baked_triangles"] = self.last.emission_baked_triangles;
            return d;
        })
        .def_property_readonly("last_warnings", [](PyRenderer& self) { return self.last_warnings; },
                               "What the last render() could not do as asked (list of str).")
        .def("clear_scene", [](PyRenderer& self) {
                 py::gil_scoped_release release;
                 self.get().clear_scene();
             },
             "Drops the scene and keeps the GL context, compiled programs and keyed images for the next one.")
        .def("release_scene_memory", [](PyRenderer& self) {
                 py::gil_scoped_release release;
                 self.get().release_scene_memory();
             },
             "Drops the scene, kept meshes and images, frame targets and shadow maps; keeps the GL context and "
             "the compiled programs (what a render without Persistent Data keeps for the next one).")
        .def("cancel", [](PyRenderer& self) { self.get().cancel(); },
             "Stop a render() running on another thread at its next sample (it raises Cancelled).")
        .def("add_mesh",
             [](PyRenderer& self, const py::object& positions, const py::object& indices,
                const py::object& corner_normals, const py::object& corner_uvs,
                const py::object& material_indices, const py::object& attributes, const py::object& texspace_location,
                const py::object& texspace_size, const std::string& key, const py::object& motion_positions) {
                 MeshData mesh;
                 py::ssize_t nv = 0, nt = 0, n = 0;
                 mesh.positions = borrow<float>(positions, "positions", {-1, 3}, &nv);
                 mesh.indices = borrow<std::uint32_t>(indices, "indices", {-1, 3}, &nt);
                 mesh.vertex_count = std::size_t(nv);
                 mesh.triangle_count = std::size_t(nt);
                 if (!corner_normals.is_none()) {
                     mesh.corner_normals = borrow<float>(corner_normals, "corner_normals", {-1, 3}, &n);
                     if (n != 3 * nt)
                         throw py::value_error("corner_normals: expected " + std::to_string(3 * nt) +
                                               " rows (3 per triangle), got " + std::to_string(n));
                 }
                 if (!corner_uvs.is_none()) {
                     mesh.corner_uvs = borrow<float>(corner_uvs, "corner_uvs", {-1, 2}, &n);
                     if (n != 3 * nt)
                         throw py::value_error("corner_uvs: expected " + std::to_string(3 * nt) +
                                               " rows (3 per triangle), got " + std::to_string(n));
                 }
                 if (!material_indices.is_none()) {
                     mesh.material_indices = borrow<std::int32_t>(material_indices, "material_indices", {-1}, &n);
                     if (n != nt)
                         throw py::value_error("material_indices: expected " + std::to_string(nt) +
                                               " values (one per triangle), got " + std::to_string(n));
                 }
                 if (!attributes.is_none()) {
                     // (name, (3T, C) float32 array) per attribute; the arrays
                     // must be numpy arrays (borrowed, not converted copies).
                     for (const py::handle& a : attributes) {
                         const py::tuple t = py::reinterpret_borrow<py::object>(a).cast<py::tuple>();
                         if (t.size() != 2) throw py::value_error("attributes: expected (name, array) tuples");
                         CornerAttribute attr;
                         attr.name = t[0].cast<std::string>();
                         const std::string what = "attribute '" + attr.name + "'";
                         if (!py::isinstance<py::array>(t[1]))
                             throw py::value_error(what + ": expected a numpy array");
                         py::array arr = py::reinterpret_borrow<py::array>(t[1]);
                         if (arr.ndim() != 2) throw py::value_error(what + ": expected a (3T, C) array");
                         attr.components = int(arr.shape(1));
                         attr.data = borrow<float>(arr, what.c_str(), {3 * nt, -1});
                         mesh.attributes.push_back(attr);
                     }
                 }
                 if (!texspace_location.is_none()) mesh.texspace_location = vec3_from(texspace_location, "texspace_location");
                 if (!texspace_size.is_none()) mesh.texspace_size = vec3_from(texspace_size, "texspace_size");
                 if (!motion_positions.is_none())
                     mesh.motion_positions = borrow<float>(motion_positions, "motion_positions", {2, nv, 3});
                 py::gil_scoped_release release;
                 return self.get().add_mesh(mesh, key);
             },
             py::arg("positions"), py::arg("indices"), py::kw_only(), py::arg("corner_normals") = py::none(),
             py::arg("corner_uvs") = py::none(), py::arg("material_indices") = py::none(),
             py::arg("attributes") = py::none(), py::arg("texspace_location") = py::none(),
             py::arg("texspace_size") = py::none(), py::arg("key") = std::string(),
             py::arg("motion_positions") = py::none(),
             "motion_positions: float32 (2, V, 3), a deforming mesh's vertices at the previous and the next "
             "frame (the Vector pass), object space, in the order of positions.")
        .def("find_mesh",
             [](PyRenderer& self, const std::string& key) -> py::object {
                 std::int64_t id;
                 {
                     py::gil_scoped_release release;
                     id = self.get().find_mesh(key);
                 }
                 if (id < 0) return py::none();
                 return py::int_(id);
             },
             py::arg("key"), "The id of a mesh kept (by key, add_mesh(..., key=)) from the previous scene, "
             "or None; the current scene then counts as using it.")
        .def("add_image",
             [](PyRenderer& self, const py::object& pixels, const std::string& key) {
                 ImageData image;
                 py::ssize_t h = 0;
                 if (!py::isinstance<py::array>(pixels)) throw py::value_error("add_image: expected a numpy array");
                 py::array a = pixels.cast<py::array>();
                 if (a.ndim() != 3 || a.shape(2) != 4) throw py::value_error("add_image: expected an (H, W, 4) array");
                 if (a.dtype().equal(py::dtype::of<std::uint8_t>()))
                     image.bytes = borrow<std::uint8_t>(a, "add_image", {-1, -1, 4}, &h);
                 else
                     image.floats = borrow<float>(a, "add_image (uint8 or float32)", {-1, -1, 4}, &h);
                 image.height = int(h);
                 image.width = int(a.shape(1));
                 py::gil_scoped_release release;
                 return self.get().add_image(image, key);
             },
             py::arg("pixels"), py::kw_only(), py::arg("key") = std::string(),
             "An RGBA image (H, W, 4), uint8 or float32, row 0 at the bottom; returns its id. With a key "
             "(a name for its content), the image outlives clear_scene() while each scene uses it.")
        .def("find_image",
             [](PyRenderer& self, const std::string& key) -> py::object {
                 std::int64_t id;
                 {
                     py::gil_scoped_release release;
                     id = self.get().find_image(key);
                 }
                 if (id < 0) return py::none();
                 return py::int_(id);
             },
             py::arg("key"), "The id of an image kept (by key) from the previous scene, or None; "
             "the current scene then counts as using it.")
        .def("add_graph_material",
             [](PyRenderer& self, const py::dict& graph, const py::object& pass_index, const py::object& light_emission,
               bool emission_varies, bool blend, std::uint32_t crypto, bool emits) {
                 Material base;
                 base.emission_varies = emission_varies;
                 base.graph_may_emit = emits;
                 base.blend = blend;
                 base.crypto = crypto;
                 base.pass_index = index_from(pass_index, "add_graph_material: pass_index");
                 if (!light_emission.is_none()) base.emission = vec3_from(light_emission, "add_graph_material: light_emission");
                 MaterialGraph g = graph_from_python(graph);
                 py::gil_scoped_release release;
                 return self.get().add_graph_material(base, g);
             },
             py::arg("graph"), py::kw_only(), py::arg("pass_index") = 0, py::arg("light_emission") = py::none(),
             py::arg("emission_varies") = false, py::arg("blend") = false, py::arg("crypto") = 0u,
             py::arg("emits") = true,
             "A node material from the add-on's graph dict (materials/builder.py); returns the material id. "
             "light_emission: the radiance its surface emits when the graph makes it a constant (the mesh "
             "then lights other surfaces); the graph alone decides what its pixels show. emission_varies: its "
             "emission varies over the surface (the renderer bakes it to light other surfaces). blend: Blend mode, "
             "drawn by the forward pass (Material::blend). emits: False when the graph emits nothing for any "
             "ray (Material::graph_may_emit).")
        .def("add_material",
             [](PyRenderer& self, const py::object& base_color, float metallic, float roughness, float specular,
                float specular_tint, float sheen, float sheen_tint, float clearcoat, float clearcoat_roughness,
                const py::object& emission, float emission_strength, float alpha, float diffuse_roughness,
                int glossy_model, const py::object& pass_index, int mix_with, float mix_probability, bool blend,
                std::uint32_t crypto, bool holdout) {
                 Material mat;
                 mat.blend = blend;
                 mat.crypto = crypto;
                 mat.holdout = holdout;
                 mat.base_color = vec3_from(base_color, "base_color");
                 mat.metallic = metallic;
                 mat.roughness = roughness;
                 mat.specular = specular;
                 mat.specular_tint = specular_tint;
                 mat.sheen = sheen;
                 mat.sheen_tint = sheen_tint;
                 mat.clearcoat = clearcoat;
                 mat.clearcoat_roughness = clearcoat_roughness;
                 mat.emission = vec3_from(emission, "emission");
                 mat.emission_strength = emission_strength;
                 mat.alpha = alpha;
                 mat.diffuse_roughness = diffuse_roughness;
                 mat.glossy_model = glossy_model;
                 mat.pass_index = index_from(pass_index, "add_material: pass_index");
                 mat.mix_with = mix_with;
                 mat.mix_probability = mix_probability;
                 return self.get().add_material(mat);
             },
             py::kw_only(), py::arg("base_color") = py::make_tuple(0.8, 0.8, 0.8), py::arg("metallic") = 0.0f,
             py::arg("roughness") = 0.5f, py::arg("specular") = 0.5f, py::arg("specular_tint") = 0.0f,
             py::arg("sheen") = 0.0f, py::arg("sheen_tint") = 0.5f, py::arg("clearcoat") = 0.0f,
             py::arg("clearcoat_roughness") = 0.03f, py::arg("emission") = py::make_tuple(0.0, 0.0, 0.0),
             py::arg("emission_strength") = 1.0f, py::arg("alpha") = 1.0f, py::arg("diffuse_roughness") = -1.0f, py::arg("glossy_model") = 0,
             py::arg("pass_index") = 0, py::arg("mix_with") = -1, py::arg("mix_probability") = 0.0f,
             py::arg("blend") = false, py::arg("crypto") = 0u, py::arg("holdout") = false)
        .def("add_instances",
             [](PyRenderer& self, const py::object& mesh_id_obj, const py::object& matrices,
                const py::object& object_indices, const py::object& material_slots, bool cast_shadow,
                const py::object& colors_obj, const py::object& randoms_obj, const py::object& crypto_obj,
                bool holdout, std::uint32_t light_group, const py::object& terminator_obj,
                const py::object& motion_obj, bool shadow_catcher) {
                 const std::uint32_t mesh_id = index_from(mesh_id_obj, "add_instances: mesh_id");
                 py::ssize_t n = 0, k = 0;
                 const double* rows = borrow<double>(matrices, "matrices", {-1, 4, 4}, &n);
                 // Row-major numpy (Blender Matrix order) -> column-major.
                 std::vector<double> cols(std::size_t(n) * 16);
                 for (py::ssize_t i = 0; i < n; ++i)
                     for (int r = 0; r < 4; ++r)
                         for (int c = 0; c < 4; ++c) cols[std::size_t(i * 16 + c * 4 + r)] = rows[i * 16 + r * 4 + c];
                 const std::uint32_t* ids = nullptr;
                 if (!object_indices.is_none()) {
                     ids = borrow<std::uint32_t>(object_indices, "object_indices", {-1}, &k);
                     if (k != n)
                         throw py::value_error("object_indices: expected " + std::to_string(n) + " values, got " +
                                               std::to_string(k));
                 }
                 std::vector<std::uint32_t> slots;
                 if (!material_slots.is_none()) {
                     if (!py::isinstance<py::iterable>(material_slots) || py::isinstance<py::str>(material_slots))
                         throw py::value_error("material_slots: expected a sequence of material ids");
                     for (const py::handle& h : material_slots)
                         slots.push_back(index_from(h, "material_slots: element " + std::to_string(slots.size())));
                 }
                 const float* colors = nullptr;
                 const float* randoms = nullptr;
                 if (!colors_obj.is_none()) colors = borrow<float>(colors_obj, "colors", {n, 4});
                 if (!randoms_obj.is_none()) randoms = borrow<float>(randoms_obj, "randoms", {n});
                 const std::uint32_t* crypto = nullptr;
                 if (!crypto_obj.is_none()) crypto = borrow<std::uint32_t>(crypto_obj, "crypto", {n, 2});
                 const float* terminator = nullptr;
                 if (!terminator_obj.is_none())
                     terminator = borrow<float>(terminator_obj, "terminator_offsets", {n});
                 std::vector<double> motion;
                 if (!motion_obj.is_none()) {
                     const double* m = borrow<double>(motion_obj, "motion", {n, 2, 4, 4});
                     motion.resize(std::size_t(n) * 32);
                     for (py::ssize_t i = 0; i < 2 * n; ++i)
                         for (int r = 0; r < 4; ++r)
                             for (int c = 0; c < 4; ++c)
                                 motion[std::size_t(i * 16 + c * 4 + r)] = m[i * 16 + r * 4 + c];
                 }
                 py::gil_scoped_release release;
                 self.get().add_instances(mesh_id, cols.data(), std::size_t(n), ids, slots, cast_shadow, colors, randoms,
                                          crypto, holdout, light_group, terminator,
                                          motion.empty() ? nullptr : motion.data(), shadow_catcher);
             },
             py::arg("mesh_id"), py::arg("matrices"), py::kw_only(), py::arg("object_indices") = py::none(),
             py::arg("material_slots") = py::none(), py::arg("cast_shadow") = true, py::arg("colors") = py::none(),
             py::arg("randoms") = py::none(), py::arg("crypto") = py::none(), py::arg("holdout") = false,
             py::arg("light_group") = 0u, py::arg("terminator_offsets") = py::none(),
             py::arg("motion") = py::none(), py::arg("shadow_catcher") = false,
             "crypto: uint32 (n, 2), each instance's Cryptomatte object and asset hashes (MurmurHash3_32 of "
             "the names). holdout: the instances are holes in the image (Object > Visibility > Holdout). "
             "terminator_offsets: float32 (n,), each instance's Shadow Terminator Geometry Offset (Cycles' "
             "object setting; 0, the default here, moves no shadow ray). motion: float64 (n, 2, 4, 4), each "
             "instance's world matrices at the previous and the next frame (the Vector pass). shadow_catcher: "
             "Object > Visibility > Shadow Catcher.")
        .def("add_light",
             [](PyRenderer& self, const std::string& type, const py::object& matrix, const py::object& color,
                float energy, float radius, float spot_size, float spot_blend, float angle, const std::string& shape,
                float size, float size_y, bool cast_shadow, std::uint32_t light_group) {
                 Light l;
                 l.light_group = light_group;
                 if (type == "POINT") l.type = LightType::Point;
                 else if (type == "SPOT") l.type = LightType::Spot;
                 else if (type == "SUN") l.type = LightType::Sun;
                 else if (type == "AREA") l.type = LightType::Area;
                 else throw py::value_error("add_light: type '" + type + "' is not one of POINT, SPOT, SUN, AREA");
                 if (shape == "SQUARE") l.shape = AreaShape::Square;
                 else if (shape == "RECTANGLE") l.shape = AreaShape::Rectangle;
                 else if (shape == "DISK") l.shape = AreaShape::Disk;
                 else if (shape == "ELLIPSE") l.shape = AreaShape::Ellipse;
                 else throw py::value_error("add_light: shape '" + shape + "' is not one of SQUARE, RECTANGLE, DISK, ELLIPSE");
                 if (!matrix.is_none()) l.matrix = matrix_from_python(matrix, "add_light: matrix");
                 l.color = vec3_from(color, "add_light: color");
                 l.energy = energy;
                 l.radius = radius;
                 l.spot_size = spot_size;
                 l.spot_blend = spot_blend;
                 l.angle = angle;
                 l.size = size;
                 l.size_y = size_y;
                 l.cast_shadow = cast_shadow;
                 self.get().add_light(l);
             },
             py::kw_only(), py::arg("type") = "POINT", py::arg("matrix") = py::none(),
             py::arg("color") = py::make_tuple(1.0, 1.0, 1.0), py::arg("energy") = 10.0f, py::arg("radius") = 0.25f,
             py::arg("spot_size") = 0.785398f, py::arg("spot_blend") = 0.15f, py::arg("angle") = 0.00918043f,
             py::arg("shape") = "SQUARE", py::arg("size") = 0.25f, py::arg("size_y") = 0.25f,
             py::arg("cast_shadow") = true, py::arg("light_group") = 0u)
        .def("set_world", [](PyRenderer& self, const py::object& color, const py::object& graph,
                             std::uint32_t light_group) {
            World w;
            w.light_group = light_group;
            w.color = vec3_from(color, "set_world: color");
            if (graph.is_none()) {
                self.get().set_world(w);
                return;
            }
            if (!py::isinstance<py::dict>(graph)) throw py::value_error("set_world: graph must be a dict or None");
            MaterialGraph g = graph_from_python(graph.cast<py::dict>());
            py::gil_scoped_release release;
            self.get().set_world(w, &g);
        }, py::kw_only(), py::arg("color"), py::arg("graph") = py::none(), py::arg("light_group") = 0u,
        "The world: a constant colour, or (graph) a world node tree's graph dict "
        "(materials/builder.py build_world_graph), baked into an environment map.")
        .def("render",
             [](PyRenderer& self, const Camera& camera, int width, int height, const std::vector<std::string>& passes,
                bool film_transparent, float mist_start, float mist_depth, const std::string& mist_falloff,
                int samples, float filter_width, bool light_culling, float light_threshold, int light_samples, bool shadows,
                int shadow_resolution, float shadow_quality, bool shadow_rays, float alpha_threshold,
                const std::vector<std::string>& cryptomatte, int cryptomatte_levels,
                const std::vector<std::pair<std::string, std::string>>& aovs, int light_groups,
                int preview_interval_ms, const std::string& preview_pass, bool motion_blur, bool filter_splat,
                bool visibility_buffer, bool count_shadow_fragments, int emission_samples,
                bool exact_transparent_planes) {
                 RenderSettings s;
                 s.exact_transparent_planes = exact_transparent_planes;
                 s.emission_samples = emission_samples;
                 s.count_shadow_fragments = count_shadow_fragments;
                 s.filter_splat = filter_splat;
                 s.visibility_buffer = visibility_buffer;
                 s.motion_blur = motion_blur;
                 s.preview_interval_ms = preview_interval_ms;
                 {
                     auto p = pass_from_name(preview_pass);
                     if (!p) throw py::value_error("render: unknown preview_pass '" + preview_pass + "'");
                     s.preview_pass = *p;
                 }
                 s.width = width;
                 s.height = height;
                 for (const std::string& name : passes) {
                     auto p = pass_from_name(name);
                     if (!p) throw py::value_error("render: unknown pass '" + name + "'");
                     s.passes.insert(*p);
                 }
                 s.film_transparent = film_transparent;
                 s.mist.start = mist_start;
                 s.mist.depth = mist_depth;
                 if (mist_falloff == "QUADRATIC") s.mist.falloff = MistFalloff::Quadratic;
                 else if (mist_falloff == "LINEAR") s.mist.falloff = MistFalloff::Linear;
                 else if (mist_falloff == "INVERSE_QUADRATIC") s.mist.falloff = MistFalloff::InverseQuadratic;
                 else throw py::value_error("render: mist_falloff '" + mist_falloff + "' is not one of QUADRATIC, LINEAR, INVERSE_QUADRATIC");
                 s.samples = samples;
                 s.filter_width = filter_width;
                 s.light_culling = light_culling;
                 s.light_threshold = light_threshold;
                 s.light_samples = light_samples;
                 s.shadows = shadows;
                 s.shadow_resolution = shadow_resolution;
                 s.shadow_quality = shadow_quality;
                 s.shadow_rays = shadow_rays;
                 s.alpha_threshold = alpha_threshold;
                 for (const std::string& name : cryptomatte) {
                     bool known = false;
                     for (CryptomatteKind k : {CryptomatteKind::Object, CryptomatteKind::Material, CryptomatteKind::Asset})
                         if (name == cryptomatte_name(k)) {
                             s.cryptomatte.push_back(k);
                             known = true;
                         }
                     if (!known)
                         throw py::value_error("render: unknown cryptomatte layer '" + name +
                                               "' (CryptoObject, CryptoMaterial, CryptoAsset)");
                 }
                 s.cryptomatte_levels = cryptomatte_levels;
                 for (const auto& [name, type] : aovs) {
                     if (type != "COLOR" && type != "VALUE")
                         throw py::value_error("render: AOV '" + name + "' type '" + type + "' is not COLOR or VALUE");
                     s.aovs.push_back({name, type == "COLOR"});
                 }
                 s.light_groups = light_groups;
                 FrameResult frame;
                 {
                     py::gil_scoped_release release;
                     frame = self.get().render(camera, s);
                 }
                 self.last = frame.timings;
                 self.last_warnings = frame.warnings;
                 py::dict out;
                 for (PassImage& img : frame.passes) {
                     const char* name = pass_info(img.pass).name;
                     out[name] = to_numpy(std::move(img));
                 }
                 // Cryptomatte: Blender's passes <Layer>00, 01, ... of two ranks (id, coverage) each.
                 for (const CryptomatteImage& c : frame.cryptomatte) {
                     const int passes = (c.levels + 1) / 2;
                     for (int p = 0; p < passes; ++p) {
                         py::array_t<float> a({py::ssize_t(c.height), py::ssize_t(c.width), py::ssize_t(4)});
                         float* dst = a.mutable_data();
                         const std::size_t pixels = std::size_t(c.width) * std::size_t(c.height);
                         for (std::size_t i = 0; i < pixels; ++i)
                             for (int ch = 0; ch < 4; ++ch) {
                                 const int value = 4 * p + ch;  // (id, coverage) pairs, rank by rank
                                 dst[i * 4 + ch] = value < 2 * c.levels ? c.pixels[i * 2 * c.levels + value] : 0.0f;
                             }
                         char suffix[16];
                         std::snprintf(suffix, sizeof suffix, "%02d", p);
                         out[py::str(std::string(cryptomatte_name(c.kind)) + suffix)] = a;
                     }
                 }
                 // Light groups: "#lightgroup<k>" (k from 1, the groups' indices), RGB.
                 for (std::size_t g = 0; g < frame.light_groups.size(); ++g) {
                     const std::vector<float>& rgba = frame.light_groups[g];
                     py::array_t<float> arr({py::ssize_t(height), py::ssize_t(width), py::ssize_t(3)});
                     float* dst = arr.mutable_data();
                     for (std::size_t i = 0; i < rgba.size() / 4; ++i)
                         for (int c = 0; c < 3; ++c) dst[i * 3 + c] = rgba[i * 4 + c];
                     out[py::str("#lightgroup" + std::to_string(g + 1))] = arr;
                 }
                 // Shader AOVs: by their names, RGBA or one channel.
                 for (AovImage& a : frame.aovs) {
                     const py::ssize_t channels = a.color ? 4 : 1;
                     py::array_t<float> arr({py::ssize_t(a.height), py::ssize_t(a.width), channels});
                     std::copy(a.pixels.begin(), a.pixels.end(), arr.mutable_data());
                     out[py::str(a.name)] = arr;
                 }
                 return out;
             },
             py::arg("camera"), py::arg("width"), py::arg("height"), py::kw_only(),
             py::arg("passes") = std::vector<std::string>{"Combined"}, py::arg("film_transparent") = false,
             py::arg("mist_start") = 5.0f, py::arg("mist_depth") = 25.0f, py::arg("mist_falloff") = "QUADRATIC",
             py::arg("samples") = 1, py::arg("filter_width") = 1.5f, py::arg("light_culling") = true,
             py::arg("light_threshold") = 1e-3f, py::arg("light_samples") = 0, py::arg("shadows") = true, py::arg("shadow_resolution") = 1024,
             py::arg("shadow_quality") = 1.0f, py::arg("shadow_rays") = false, py::arg("alpha_threshold") = 0.5f,
             py::arg("cryptomatte") = std::vector<std::string>{}, py::arg("cryptomatte_levels") = 6,
             py::arg("aovs") = std::vector<std::pair<std::string, std::string>>{}, py::arg("light_groups") = 0,
             py::arg("preview_interval_ms") = -1, py::arg("preview_pass") = "Combined",
             py::arg("motion_blur") = false, py::arg("filter_splat") = true, py::arg("visibility_buffer") = true,
             py::arg("count_shadow_fragments") = false, py::arg("emission_samples") = 1,
             py::arg("exact_transparent_planes") = true)
        .def("preview",
             [](const PyRenderer& self, std::uint64_t since) -> py::object {
                 if (!self.renderer) throw Error("the renderer was closed");
                 PreviewImage image;
                 bool fresh;
                 {
                     py::gil_scoped_release release;
                     fresh = self.renderer->preview(since, image);
                 }
                 if (!fresh) return py::none();
                 py::object pixels = py::none();
                 if (!image.pixels.empty()) {
                     PassImage img;
                     img.width = image.width;
                     img.height = image.height;
                     img.channels = 4;
                     img.pixels = std::move(image.pixels);
                     pixels = to_numpy(std::move(img));
                 }
                 return py::make_tuple(image.version, image.samples_done, image.samples_total, pixels);
             },
             py::arg("since") = 0,
             "The newest estimate of the preview_pass of a render running with preview_interval_ms >= 0, if newer "
             "than version `since`: (version, samples_done, samples_total, (H, W, 4) float32 array or "
             "None before the first sample), else None. Never waits for the render.");
}

}  // namespace deferred::python

#include "builtin_scenes.h"

#include <glm/glm.hpp>

#include <cmath>
#include <random>

namespace deferred::tools {

MeshData MeshArrays::view() const {
    MeshData m;
    m.positions = positions.data();
    m.vertex_count = positions.size() / 3;
    m.indices = indices.data();
    m.triangle_count = indices.size() / 3;
    m.corner_normals = normals.empty() ? nullptr : normals.data();
    m.corner_uvs = uvs.empty() ? nullptr : uvs.data();
    return m;
}

MeshArrays make_plane(float h, int n) {
    MeshArrays m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            m.positions.insert(m.positions.end(), {-h + 2 * h * i / n, -h + 2 * h * j / n, 0.0f});
        }
    auto idx = [n](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = idx(i, j), b = idx(i + 1, j), c = idx(i + 1, j + 1), d = idx(i, j + 1);
            for (std::uint32_t v : {a, b, c, a, c, d}) {
                m.indices.push_back(v);
                m.normals.insert(m.normals.end(), {0.0f, 0.0f, 1.0f});
                m.uvs.insert(m.uvs.end(), {0.5f + m.positions[3 * v] / (2 * h), 0.5f + m.positions[3 * v + 1] / (2 * h)});
            }
        }
    return m;
}

MeshArrays make_uv_sphere(float radius, int segments, int rings) {
    MeshArrays m;
    std::vector<float> vnormals;
    for (int r = 0; r <= rings; ++r) {
        const double theta = M_PI * r / rings;
        for (int s = 0; s <= segments; ++s) {
            const double phi = 2 * M_PI * s / segments;
            const float x = float(std::sin(theta) * std::cos(phi)), y = float(std::sin(theta) * std::sin(phi)),
                        z = float(std::cos(theta));
            m.positions.insert(m.positions.end(), {radius * x, radius * y, radius * z});
            vnormals.insert(vnormals.end(), {x, y, z});
        }
    }
    auto idx = [segments](int s, int r) { return std::uint32_t(r * (segments + 1) + s); };
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const std::uint32_t a = idx(s, r), b = idx(s, r + 1), c = idx(s + 1, r + 1), d = idx(s + 1, r);
            for (std::uint32_t v : {a, b, c, a, c, d}) {
                m.indices.push_back(v);
                m.normals.insert(m.normals.end(), {vnormals[3 * v], vnormals[3 * v + 1], vnormals[3 * v + 2]});
                m.uvs.insert(m.uvs.end(), {float(v % (segments + 1)) / segments, float(v / (segments + 1)) / rings});
            }
        }
    return m;
}

MeshArrays make_box(float hx, float hy, float hz) {
    MeshArrays m;
    const float n[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& f : n) {
        glm::vec3 N(f[0], f[1], f[2]);
        glm::vec3 U = std::abs(N.z) > 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
        glm::vec3 V = glm::cross(N, U);
        const glm::vec3 h(hx, hy, hz);
        const std::uint32_t base = std::uint32_t(m.positions.size() / 3);
        for (auto [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
            glm::vec3 p = (N + float(a) * U + float(b) * V) * h;
            m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
        }
        // Wind counter-clockwise seen from outside.
        const bool flip = glm::dot(glm::cross(U, V), N) < 0;
        const std::uint32_t quad[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; ++k) {
            const std::uint32_t q = flip ? quad[5 - k] : quad[k];
            m.indices.push_back(base + q);
            m.normals.insert(m.normals.end(), {N.x, N.y, N.z});
            m.uvs.insert(m.uvs.end(), {0.0f, 0.0f});
        }
    }
    return m;
}

Mat4d translation(double x, double y, double z) {
    Mat4d m = identity_matrix();
    m[12] = x;
    m[13] = y;
    m[14] = z;
    return m;
}

Mat4d scale_translation(double s, double x, double y, double z) {
    Mat4d m = translation(x, y, z);
    m[0] = m[5] = m[10] = s;
    return m;
}

Mat4d look_at(const double eye[3], const double target[3], const double up_in[3]) {
    glm::dvec3 e(eye[0], eye[1], eye[2]), t(target[0], target[1], target[2]);
    glm::dvec3 up = up_in ? glm::dvec3(up_in[0], up_in[1], up_in[2]) : glm::dvec3(0, 0, 1);
    glm::dvec3 z = glm::normalize(e - t);  // camera looks down -Z
    if (std::abs(glm::dot(z, glm::normalize(up))) > 0.999) up = glm::dvec3(0, 1, 0);
    glm::dvec3 x = glm::normalize(glm::cross(up, z));
    glm::dvec3 y = glm::cross(z, x);
    Mat4d m = identity_matrix();
    for (int r = 0; r < 3; ++r) {
        m[std::size_t(0 + r)] = x[r];
        m[std::size_t(4 + r)] = y[r];
        m[std::size_t(8 + r)] = z[r];
        m[std::size_t(12 + r)] = e[r];
    }
    return m;
}

Camera build_showcase(Renderer& r, int extra_point_lights, const double offset[3]) {
    const double o[3] = {offset ? offset[0] : 0.0, offset ? offset[1] : 0.0, offset ? offset[2] : 0.0};
    auto moved = [&](Mat4d m) {
        for (int k = 0; k < 3; ++k) m[std::size_t(12 + k)] += o[k];
        return m;
    };
    MeshArrays floor = make_plane(12.0f, 4);
    MeshArrays sphere = make_uv_sphere(0.4f, 48, 24);
    MeshArrays box = make_box(0.5f, 0.5f, 0.5f);
    const std::uint32_t floor_mesh = r.add_mesh(floor.view());
    const std::uint32_t sphere_mesh = r.add_mesh(sphere.view());
    const std::uint32_t box_mesh = r.add_mesh(box.view());

    Material floor_mat;
    floor_mat.base_color = {0.6f, 0.6f, 0.6f};
    floor_mat.roughness = 0.7f;
    floor_mat.pass_index = 1;
    const std::uint32_t floor_id = r.add_material(floor_mat);
    Mat4d I = moved(identity_matrix());
    std::uint32_t obj = 1;
    r.add_instances(floor_mesh, I.data(), 1, &obj, {floor_id});

    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) {
            Material m;
            m.base_color = {0.8f, 0.3f + 0.1f * j, 0.2f + 0.15f * i};
            m.roughness = 0.05f + 0.2f * i;
            m.metallic = 0.25f * j;
            if (i == 4 && j == 0) { m.clearcoat = 1.0f; m.sheen = 0.5f; }
            m.pass_index = std::uint32_t(10 + j * 5 + i);
            const std::uint32_t id = r.add_material(m);
            Mat4d t = moved(translation(-2.0 + i, -2.0 + j, 0.4));
            std::uint32_t o = std::uint32_t(100 + j * 5 + i);
            r.add_instances(sphere_mesh, t.data(), 1, &o, {id});
        }
    Material emissive;
    emissive.base_color = {0.1f, 0.1f, 0.1f};
    emissive.emission = {1.0f, 0.5f, 0.2f};
    emissive.emission_strength = 3.0f;
    const std::uint32_t emissive_id = r.add_material(emissive);
    Mat4d bt = moved(translation(3.2, 0.0, 0.5));
    std::uint32_t box_obj = 2;
    r.add_instances(box_mesh, bt.data(), 1, &box_obj, {emissive_id});

    Light point;
    point.type = LightType::Point;
    point.matrix = moved(translation(-3, -3, 3));
    point.energy = 400;
    point.radius = 0.3f;
    r.add_light(point);
    Light spot;
    spot.type = LightType::Spot;
    const double spot_eye[3] = {3, -3, 4}, spot_target[3] = {1, -1, 0};
    spot.matrix = moved(look_at(spot_eye, spot_target));
    spot.energy = 800;
    spot.spot_size = 0.8f;
    spot.color = {1.0f, 0.8f, 0.6f};
    r.add_light(spot);
    Light sun;
    sun.type = LightType::Sun;
    const double sun_eye[3] = {1, 2, 3}, origin[3] = {0, 0, 0};
    sun.matrix = moved(look_at(sun_eye, origin));
    sun.energy = 1.5f;
    r.add_light(sun);
    Light area;
    area.type = LightType::Area;
    const double area_eye[3] = {0, 3, 2.5};
    area.matrix = moved(look_at(area_eye, origin));
    area.shape = AreaShape::Rectangle;
    area.size = 2.0f;
    area.size_y = 1.0f;
    area.energy = 300;
    area.color = {0.6f, 0.8f, 1.0f};
    r.add_light(area);

    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < extra_point_lights; ++i) {
        Light l;
        l.type = LightType::Point;
        l.matrix = moved(translation(-10 + 20 * u(rng), -10 + 20 * u(rng), 0.2 + 1.5 * u(rng)));
        l.energy = 5 + 20 * u(rng);
        l.radius = 0.05f;
        l.color = {u(rng), u(rng), u(rng)};
        r.add_light(l);
    }
    World w;
    w.color = {0.05f, 0.05f, 0.05f};
    r.set_world(w);

    Camera cam;
    const double eye[3] = {0, -8, 5}, target[3] = {0, 0, 0.3};
    cam.matrix = moved(look_at(eye, target));
    cam.lens = 35.0f;
    return cam;
}

}  // namespace deferred::tools

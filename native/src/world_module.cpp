#include "world_module.h"

#include "material_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace deferred {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Blender's scene-linear luminance (Rec.709), as the add-on and Cycles use it.
double luminance(const float* rgb) { return 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2]; }

// world_lib.glsl's mapping (Cycles' equirectangular range (-2pi, pi, -pi, pi)).
glm::dvec3 uv_to_direction(double u, double v) {
    const double phi = kPi - 2.0 * kPi * u, theta = kPi * (1.0 - v);
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

glm::dvec2 direction_to_uv(const glm::dvec3& d) {
    return {(std::atan2(d.y, d.x) - kPi) / (-2.0 * kPi), (std::acos(std::clamp(d.z, -1.0, 1.0)) - kPi) / -kPi};
}

glm::dvec3 uniform_sphere(double a, double b) {
    const double z = 1.0 - 2.0 * a, phi = 2.0 * kPi * b, r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// The largest k in [0, n) with cdf[k] <= x (cdf[0] = 0 <= x < 1 = cdf[n]).
std::size_t find(const double* cdf, std::size_t n, double x) {
    std::size_t lo = 0, hi = n;
    while (hi - lo > 1) {
        const std::size_t mid = (lo + hi) / 2;
        if (cdf[mid] <= x) lo = mid; else hi = mid;
    }
    return lo;
}

}  // namespace

double WorldModule::prepare(ShaderLibrary& shaders, MaterialModule& materials, std::int32_t graph) {
    release();
    if (graph < 0) return 0.0;
    const auto start = std::chrono::steady_clock::now();
    const std::uint32_t g = std::uint32_t(graph);
    // The map's size: an environment image's own (a bilinear lookup of the
    // bake is then the image's; see world_lib.glsl), capped; 2:1.
    const std::array<int, 2> image = materials.largest_image(g);
    int width = image[0] > 0 ? std::max(image[0], 2 * image[1]) : kDefaultWidth;
    width = std::clamp(width, 64, kMaxWidth);
    width_ = width;
    height_ = width / 2;
    radiance_ = bake(shaders, materials, g, true);
    // Camera rays see another world than light does: Light Path tricks, and
    // a sky's sun disc, which lights as a lamp (node_sky_lib.glsl).
    if (materials.calls(g, "node_light_path") || materials.calls(g, "node_tex_sky_nishita"))
        camera_ = bake(shaders, materials, g, false);

    std::vector<float> rgba(std::size_t(width_) * std::size_t(height_) * 4);
    glGetTextureImage(radiance_.get(), 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
    check_gl("reading the world map back");
    build_distribution(rgba);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Texture WorldModule::bake(ShaderLibrary& shaders, MaterialModule& materials, std::uint32_t graph, bool lighting) {
    ShaderVariant v;
    v.defines.push_back("MATERIAL_IMAGE_COUNT " + std::to_string(materials.image_count(graph)));
    if (lighting) v.defines.push_back("WORLD_LIGHTING");
    const GLuint program = shaders.compute_program("world_bake_comp.glsl", v,
                                                   {{kMaterialGraphFile, materials.graph_source(shaders, graph)}});
    Texture map = make_texture_2d(GL_RGBA32F, width_, height_, lighting ? "world map (light)" : "world map (camera)");
    glTextureParameteri(map.get(), GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(map.get(), GL_TEXTURE_WRAP_T, GL_REPEAT);
    glTextureParameteri(map.get(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(map.get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glUseProgram(program);
    glUniform1i(0, GLint(materials.constants_offset(graph)));
    materials.bind_constants();
    materials.bind_images(graph);
    glBindImageTexture(IMG_WORLD_BAKE, map.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glDispatchCompute(GLuint((width_ + 7) / 8), GLuint((height_ + 7) / 8), 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    check_gl("baking the world map");
    return map;
}

void WorldModule::build_distribution(const std::vector<float>& rgba) {
    const std::size_t W = std::size_t(width_), H = std::size_t(height_);
    row_cdf_.assign(H + 1, 0.0);
    col_cdf_.assign(H * (W + 1), 0.0);
    // The lookup is bilinear: inside a texel's cell the radiance blends its
    // neighbours', so a dark texel beside a bright one (a sun's disk) would be
    // drawn rarely yet return much of the bright one's light: fireflies.
    // Each cell is weighted by the largest luminance of the 3 x 3 texels
    // around it (a conservative density; the estimate stays unbiased).
    std::vector<double> lum(W * H);
    for (std::size_t t = 0; t < W * H; ++t) lum[t] = std::max(0.0, luminance(&rgba[t * 4]));
    std::vector<double> row_max(W * H);
    for (std::size_t j = 0; j < H; ++j)
        for (std::size_t i = 0; i < W; ++i) {
            const double* r = &lum[j * W];
            row_max[j * W + i] = std::max({r[(i + W - 1) % W], r[i], r[(i + 1) % W]});
        }
    glm::dvec3 sum(0.0);
    for (std::size_t j = 0; j < H; ++j) {
        // Texel rows have solid angle (2 pi / W)(pi / H) sin(theta) at their centre.
        const double sin_theta = std::sin(kPi * (double(j) + 0.5) / double(H));
        double* col = &col_cdf_[j * (W + 1)];
        const std::size_t below = (j + H - 1) % H, above = (j + 1) % H;  // the lookup repeats in v too
        for (std::size_t i = 0; i < W; ++i) {
            const float* t = &rgba[(j * W + i) * 4];
            const double weight = std::max({row_max[below * W + i], row_max[j * W + i], row_max[above * W + i]});
            col[i + 1] = col[i] + weight * sin_theta;
            sum += glm::dvec3(t[0], t[1], t[2]) * sin_theta;
        }
        const double row = col[W];
        for (std::size_t i = 1; i <= W; ++i) col[i] = row > 0.0 ? col[i] / row : double(i) / double(W);
        col[W] = 1.0;
        row_cdf_[j + 1] = row_cdf_[j] + row;
    }
    const double total = row_cdf_[H];
    for (std::size_t j = 1; j <= H; ++j) row_cdf_[j] = total > 0.0 ? row_cdf_[j] / total : double(j) / double(H);
    row_cdf_[H] = 1.0;
    // Mean over the sphere: sum L dOmega / (4 pi), dOmega = 2 pi^2 sin / (W H).
    mean_ = sum * (2.0 * kPi * kPi / double(W * H)) / (4.0 * kPi);

    std::vector<float> gpu(row_cdf_.size() + col_cdf_.size());
    std::copy(row_cdf_.begin(), row_cdf_.end(), gpu.begin());
    std::copy(col_cdf_.begin(), col_cdf_.end(), gpu.begin() + std::ptrdiff_t(row_cdf_.size()));
    cdf_buffer_ = make_storage_buffer(gpu.data(), gpu.size() * sizeof(float), "world CDF");
}

double WorldModule::pdf(const glm::dvec3& d) const {
    const double uniform = WORLD_UNIFORM_FRACTION / (4.0 * kPi);
    if (!has_map()) return 1.0 / (4.0 * kPi);
    const std::size_t W = std::size_t(width_), H = std::size_t(height_);
    const glm::dvec2 uv = direction_to_uv(d);
    const double fu = uv.x - std::floor(uv.x);
    const std::size_t i = std::min(W - 1, std::size_t(std::max(0.0, fu * double(W))));
    const std::size_t j = std::min(H - 1, std::size_t(std::max(0.0, uv.y * double(H))));
    const double p_row = row_cdf_[j + 1] - row_cdf_[j];
    const double* col = &col_cdf_[j * (W + 1)];
    const double p_col = col[i + 1] - col[i];
    const double s = std::sqrt(std::max(0.0, 1.0 - d.z * d.z));
    const double lum = s > 0.0 ? p_row * p_col * double(W) * double(H) / (2.0 * kPi * kPi * s) : 0.0;
    return uniform + (1.0 - WORLD_UNIFORM_FRACTION) * lum;
}

WorldDirection WorldModule::occlusion_direction(const std::array<float, 2>& u) const {
    WorldDirection r;
    if (!has_map()) {
        r.dir = uniform_sphere(u[0], u[1]);
        r.pair_pdf = 1.0 / (2.0 * kPi);
        return r;
    }
    const double f = WORLD_UNIFORM_FRACTION;
    if (double(u[0]) < f) {
        r.dir = uniform_sphere(double(u[0]) / f, u[1]);
    } else {
        const std::size_t W = std::size_t(width_), H = std::size_t(height_);
        const double y = std::min((double(u[0]) - f) / (1.0 - f), std::nextafter(1.0, 0.0));
        const double x = std::min(double(u[1]), std::nextafter(1.0, 0.0));
        const std::size_t j = find(row_cdf_.data(), H, y);
        const double y0 = row_cdf_[j], y1 = row_cdf_[j + 1];
        const double* col = &col_cdf_[j * (W + 1)];
        const std::size_t i = find(col, W, x);
        const double x0 = col[i], x1 = col[i + 1];
        const double fy = y1 > y0 ? std::clamp((y - y0) / (y1 - y0), 0.0, 1.0) : 0.5;
        const double fx = x1 > x0 ? std::clamp((x - x0) / (x1 - x0), 0.0, 1.0) : 0.5;
        r.dir = uv_to_direction((double(i) + fx) / double(W), (double(j) + fy) / double(H));
    }
    r.pair_pdf = pdf(r.dir) + pdf(-r.dir);
    return r;
}

void WorldModule::add_defines(ShaderVariant& variant) const {
    if (has_map()) variant.defines.push_back("HAS_WORLD_MAP");
}

void WorldModule::bind() const {
    if (!has_map()) return;
    glBindTextureUnit(TEX_WORLD_RADIANCE, radiance_.get());
    glBindTextureUnit(TEX_WORLD_CAMERA, camera_ ? camera_.get() : radiance_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_WORLD_CDF, cdf_buffer_.get());
}

}  // namespace deferred

#include "motion_module.h"

#include "../../shaders/shader_defines.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace deferred {

DecomposedTransform decompose_transform(const glm::dmat4& m) {
    DecomposedTransform d;
    d.translation = glm::dvec3(m[3]);
    const glm::dmat3 M(m);
    glm::dmat3 R = M;
    if (std::abs(glm::determinant(R)) > 1e-300) {
        for (int iteration = 0; iteration < 100; ++iteration) {
            const glm::dmat3 next = 0.5 * (R + glm::transpose(glm::inverse(R)));
            double norm = 0.0;
            for (int row = 0; row < 3; ++row)
                norm = std::max(norm, std::abs(R[0][row] - next[0][row]) + std::abs(R[1][row] - next[1][row]) +
                                          std::abs(R[2][row] - next[2][row]));
            R = next;
            if (norm <= 1e-12) break;
        }
    } else {
        R = glm::dmat3(1.0);  // a degenerate matrix: no rotation to extract
    }
    if (glm::determinant(R) < 0.0) R = -R;
    const glm::dquat q = glm::quat_cast(R);
    d.rotation = glm::dvec4(q.x, q.y, q.z, q.w);
    d.stretch = glm::transpose(R) * M;
    return d;
}

glm::dmat4 compose_transform(const DecomposedTransform& d) {
    const glm::dquat q(d.rotation.w, d.rotation.x, d.rotation.y, d.rotation.z);
    glm::dmat4 m(glm::mat3_cast(glm::normalize(q)) * d.stretch);
    m[3] = glm::dvec4(d.translation, 1.0);
    return m;
}

namespace {
// Cycles' quat_interpolate (util/transform.h).
glm::dvec4 quat_interpolate(const glm::dvec4& a, const glm::dvec4& b, double t) {
    const double cos_theta = glm::dot(a, b);
    if (cos_theta > 0.9995) return glm::normalize((1.0 - t) * a + t * b);
    const double theta = std::acos(std::clamp(cos_theta, -1.0, 1.0));
    const glm::dvec4 perp = glm::normalize(b - a * cos_theta);
    return a * std::cos(theta * t) + perp * std::sin(theta * t);
}
}  // namespace

glm::dmat4 interpolate_motion(const glm::dmat4& previous, const glm::dmat4& now, const glm::dmat4& next, double r) {
    DecomposedTransform steps[3] = {decompose_transform(previous), decompose_transform(now),
                                    decompose_transform(next)};
    for (int i = 1; i < 3; ++i)  // the shortest way round (transform_motion_decompose)
        if (glm::dot(steps[i - 1].rotation, steps[i].rotation) < 0.0) steps[i].rotation = -steps[i].rotation;
    // transform_motion_array_interpolate over 3 steps at time (r + 1) / 2.
    const double time = std::clamp(0.5 * (r + 1.0), 0.0, 1.0);
    const int step = std::min(int(time * 2.0), 1);
    const double t = time * 2.0 - step;
    const DecomposedTransform& a = steps[step];
    const DecomposedTransform& b = steps[step + 1];
    DecomposedTransform d;
    d.rotation = quat_interpolate(a.rotation, b.rotation, t);
    d.translation = (1.0 - t) * a.translation + t * b.translation;
    d.stretch = (1.0 - t) * a.stretch + t * b.stretch;
    return compose_transform(d);
}

double shutter_time(int sample) {
    double inverse = 0.0, scale = 1.0 / 3.0;
    for (unsigned n = unsigned(sample); n > 0; n /= 3u, scale /= 3.0) inverse += double(n % 3u) * scale;
    return std::fmod(0.5 + inverse, 1.0);
}

namespace {
void store(float out[16], const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) out[c * 4 + r] = float(m[c][r]);
}
}  // namespace

void MotionModule::begin(const SceneStore& scene, const Camera& camera, const CameraMatrices& cam, int width,
                         int height, GLuint vector_image, GLuint gbuffer_depth) {
    release();
    width_ = width;
    height_ = height;
    // Instances: previous and next model matrices, camera-relative to this
    // frame's camera position as the G-buffer's positions are (double until
    // the subtraction, as the renderer's own models).
    std::vector<float> motion;
    motion.reserve(scene.instance_count() * 32);
    for (const InstanceBatch& b : scene.batches()) {
        for (std::size_t i = 0; i < b.object_indices.size(); ++i) {
            for (int step = 0; step < 2; ++step) {
                const double* src = b.motion.empty() ? &b.matrices[i * 16] : &b.motion[i * 32 + std::size_t(step) * 16];
                Mat4d m;
                std::copy(src, src + 16, m.begin());
                glm::dmat4 model = to_glm(m);
                model[3] = glm::dvec4(glm::dvec3(model[3]) - cam.position, 1.0);
                float f[16];
                store(f, model);
                motion.insert(motion.end(), f, f + 16);
            }
        }
    }
    instance_motion_ = make_storage_buffer(motion.data(), motion.size() * sizeof(float), "instance motion");

    // Cameras: camera-relative world (this frame's position) -> clip, with
    // this frame's projection unjittered (Cycles' worldtoraster, and 3.4's
    // motion pass: cameratoraster x the other frame's inverse transform).
    store(center_, cam.projection * cam.view);
    for (int step = 0; step < 2; ++step) {
        glm::dmat4 view_projection = cam.projection * cam.view;
        if (camera.has_motion) {
            Camera other = camera;
            other.matrix = step == 0 ? camera.matrix_previous : camera.matrix_next;
            other.has_motion = false;
            const CameraMatrices o = build_camera(other, width, height);
            glm::dmat4 shift(1.0);
            shift[3] = glm::dvec4(cam.position - o.position, 1.0);
            view_projection = cam.projection * o.view * shift;
        }
        store(step == 0 ? previous_ : next_, view_projection);
    }

    weight_ = make_texture_2d(GL_R32F, width, height, "Vector pass sample count");
    const float zero[4] = {0, 0, 0, 0};
    glClearTexImage(weight_.get(), 0, GL_RED, GL_FLOAT, zero);
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    fbo_ = Framebuffer(fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, vector_image, 0);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT1, weight_.get(), 0);
    glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, gbuffer_depth, 0);
    const GLenum draw[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(fbo, 2, draw);
    const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw Error("Vector pass framebuffer incomplete (status 0x" + std::to_string(status) + ")");
    check_gl("Vector pass targets");
}

void MotionModule::bind(GLuint program) const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_EQUAL);  // the surface this sample's G-buffer holds
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);  // motion and count summed over the samples
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_MOTION, instance_motion_.get());
    glUseProgram(program);
    glProgramUniformMatrix4fv(program, 40, 1, GL_FALSE, center_);
    glProgramUniformMatrix4fv(program, 44, 1, GL_FALSE, previous_);
    glProgramUniformMatrix4fv(program, 48, 1, GL_FALSE, next_);
}

void MotionModule::end_draws() const {
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);  // reversed Z, the renderer's default
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void MotionModule::bind_resolve() const { glBindTextureUnit(TEX_MOTION_WEIGHT, weight_.get()); }

void MotionModule::release() {
    fbo_.reset();
    weight_.reset();
    instance_motion_.reset();
}

}  // namespace deferred

// The Vector pass (screen-space motion), as Cycles writes it
// (kernel/geom/primitive.h, primitive_motion_vector; film_write_data_passes):
// for the surface a film sample sees, the raster position its point had at
// the previous frame minus the one it has now (xy), and the one it has now
// minus the one at the next frame (zw), in pixels; summed over the samples
// that hit a surface and divided by their count, so edges average the
// surfaces' motion and the background stays 0.
//
// The caller gives the motion (Renderer::add_instances `motion`, Camera's
// previous and next matrices, MeshData::motion_positions of deforming
// meshes). Each sample, after the G-buffer that holds the data passes'
// surfaces is drawn, the visible instances are drawn again with the motion
// program (geometry_vert.glsl MOTION_PASS, motion_frag.glsl) against its
// depth with an EQUAL test (gl_Position is invariant across the programs),
// adding the motion to the Vector pass's accumulation and 1 to a count.
// Nothing exists when the pass is not asked for.
#pragma once

#include "camera.h"
#include "gl_util.h"
#include "scene_store.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>

namespace deferred {

// Motion blur: each film sample renders the scene at one time of the shutter
// (Cycles samples a time per path; one per film sample converges to the same
// average). The caller's previous / now / next matrices are Cycles' three
// motion steps at relative times -1, 0, 1 of the shutter; between them a
// transform is interpolated as Cycles does (util/transform.cpp
// transform_motion_decompose, kernel/geom/object.h
// transform_motion_array_interpolate): translation and the stretch matrix
// linearly, the rotation by slerp of its quaternion (linear above cos 0.9995),
// consecutive quaternions in one hemisphere.
struct DecomposedTransform {
    glm::dvec3 translation{0.0};
    glm::dvec4 rotation{0.0, 0.0, 0.0, 1.0};  // quaternion x, y, z, w
    glm::dmat3 stretch{1.0};                   // rotation^-1 x the linear part (scale, shear)
};
// M = T R S, R from the polar decomposition of M's linear part (Cycles'
// iteration R <- (R + R^-T) / 2, a negative determinant moved into S).
DecomposedTransform decompose_transform(const glm::dmat4& m);
glm::dmat4 compose_transform(const DecomposedTransform& d);
// The transform at relative shutter time r in [-1, 1] of the steps
// (previous, now, next).
glm::dmat4 interpolate_motion(const glm::dmat4& previous, const glm::dmat4& now, const glm::dmat4& next, double r);
// Film sample s's time on the shutter in [0, 1): 0.5 (the frame's own time)
// for sample 0, then the base-3 radical inverse shifted by 1/2, stratified
// for any number of samples and unrelated to the pixel filter's and the
// light samples' sequences.
double shutter_time(int sample);

class MotionModule {
public:
    // Packs every instance's previous and next model matrix, relative to
    // this frame's camera position (the renderer's instance order: batches,
    // then instances), the cameras' raster transforms, and allocates the
    // count target and the framebuffer accumulating into `vector_image`
    // (cleared RGBA32F) against the G-buffer's depth.
    void begin(const SceneStore& scene, const Camera& camera, const CameraMatrices& cam, int width, int height,
               GLuint vector_image, GLuint gbuffer_depth);
    bool active() const { return static_cast<bool>(fbo_); }
    // The framebuffer, blend and depth state, buffers and the program's
    // uniforms for one sample's draw of the visible instances.
    void bind(GLuint program) const;
    void end_draws() const;
    // The count target at TEX_MOTION_WEIGHT, for the resolve (passes_comp.glsl RESOLVE_MOTION).
    void bind_resolve() const;
    void release();
    static std::size_t bytes(const RenderSettings& s) { return std::size_t(s.width) * std::size_t(s.height) * 4; }

private:
    Buffer instance_motion_;
    Texture weight_;
    Framebuffer fbo_;
    int width_ = 0, height_ = 0;
    float center_[16] = {}, previous_[16] = {}, next_[16] = {};  // camera-relative world -> clip
};

}  // namespace deferred

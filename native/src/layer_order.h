// Partly transparent planar and convex surfaces composited exactly: which
// of them the forward pass (forward_module.h) can draw in Cycles' stead of
// stochastic coverage, and in which order.
//
// Why: Cycles' camera rays pass a transparent closure with weight 1 - alpha,
// exactly; the deferred path keeps a partly transparent surface in a share
// alpha of the samples (stratified, frame_lib.glsl transparency_random),
// which converges to the same image but is most of the noise of a scene
// with panes at a few samples (a pane of alpha 0.3 is seen in 1 or 2 of 4;
// the transparency sample scene: 0.4 of its squared error on the panes and
// as much again on the floor seen through them). The forward pass lights
// each layer where it is drawn and composites it with its alpha, exact at
// one sample, in the order of its draws: exact when each drawn surface
// meets a view ray at most once and the draws come nearest first along
// every ray. A plane meets a ray once, and two planar surfaces A and B are
// met in the same order by every ray from a pinhole eye when B lies wholly
// on one side of A's plane: on the eye's side, B first (a ray from the eye
// stays on that side until it crosses A's plane, at A); on the far side, A
// first (the plane test of Newell, Newell and Sancha's painter's
// algorithm, 1972). A closed convex surface (a ball, a box of glass) meets
// a ray from outside at most twice, first where it faces the eye: drawn as
// two layers, its near side then its far side, it is ordered against a
// plane wholly on one side of it the same way (two convex surfaces are not
// ordered with each other unless no ray meets both). Surfaces whose order
// that cannot settle (each crosses the other's plane, or a cycle of them)
// stay stochastic, as does every surface that is neither planar nor convex.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace deferred {

class FrameScene;
struct ViewVolume;

struct Layer {
    // A planar surface: the plane dot(normal, x) = offset (normal unit).
    // A convex one (convex): no plane to test others against.
    bool convex = false;
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double offset = 0.0;
    std::vector<glm::dvec3> corners;   // a convex polytope holding the surface (its box's corners)
    // A sphere holding it too (radius < 0: none): the tests take whichever
    // of the two bounds is tighter in each direction (a ball's box reaches
    // past it at its corners).
    glm::dvec3 center{0.0};
    double radius = -1.0;
};

// How the view's rays run: from `eye` (perspective), or all along
// `direction` (orthographic); `direction` is the view's forward axis in
// both (the layers' images on the plane across it decide which pairs a ray
// can meet together at all).
struct RayFan {
    glm::dvec3 eye{0.0};
    glm::dvec3 direction{0.0, 0.0, -1.0};
    bool orthographic = false;
};

// The layers the plane test orders, nearest first along every ray that
// meets two of them (a convex layer's two sides come together, near side
// first, in its place); unordered[i] is set for the others (it is resized to
// layers.size()). Pairs whose images across the view do not overlap (their
// corners' bounding rectangles there are apart), coplanar layers and
// layers seen edge-on need no order between them (no ray meets both, or a
// ray meets both at one point, or the edge-on one never).
std::vector<std::uint32_t> order_layers(const std::vector<Layer>& layers, const RayFan& rays,
                                               std::vector<bool>& unordered);

// The frame's choice: per material id, whether the forward pass draws it
// exactly, and per instance its place in the forward pass's order.
struct ExactLayers {
    std::vector<bool> materials;      // per material id
    std::vector<std::uint32_t> rank;  // per instance: its draw order (nearest first); UINT32_MAX: not a layer
    std::uint32_t instances = 0;      // instances in view drawn as exact layers
    bool any() const { return instances > 0; }
};

// Of the `transparent` materials (per id: partly transparent, stochastic
// otherwise), those whose every instance in `view` is planar or convex
// (GpuMesh::planar, convex), not a holdout object, and ordered by
// order_layers among the others. Instances out of view neither take part
// nor hold a material back (the camera never draws them); their shadows
// stay the stochastic ones. At most kMaxExactLayers instances are ordered
// (the test is quadratic); with more, none.
constexpr std::size_t kMaxExactLayers = 1024;
ExactLayers select_exact_layers(const FrameScene& scene, const std::vector<bool>& transparent, const ViewVolume& view);

}  // namespace deferred

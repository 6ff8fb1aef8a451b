// The film: Blender's pixel filter and the per-sample jitter that realises it.
//
// Cycles importance-samples its pixel filter (intern/cycles/scene/film.cpp,
// filter_table): each sample is taken at an offset drawn from the 1D filter,
// independently in x and y, and every sample has weight 1. A rasteriser does
// the same by jittering the whole projection by one offset per sample, so
// averaging N renders gives Cycles' filtered pixel. For Blackman-Harris
// Cycles doubles the width before tabulating, so the support is
// [-filter_width, +filter_width] pixels (1.5 px by default).
#pragma once

#include <array>
#include <vector>

namespace deferred {

// Cycles' filter_func_blackman_harris(v, width), v in [-width/2, width/2].
double blackman_harris(double v, double width);

// The taps one film sample adds to a pixel from its neighbours (the film's
// filter splatting, below). Tap k is the pixel `first + k` pixels away
// (per axis), weighted by weight[k]; the weights of an axis sum to 1.
constexpr int kMaxSplatTaps = 8;
struct SplatTaps {
    int first = 0;
    int count = 1;
    std::array<float, kMaxSplatTaps> weight{1.0f};
};

class PixelFilter {
public:
    // filter_width: Blender's render.filter_size (Cycles filter_width), pixels.
    explicit PixelFilter(float filter_width);
    // Inverse CDF of the 1D filter: u in [0,1) -> offset in pixels; u = 0.5 -> 0.
    float offset(float u) const;
    float support() const { return half_width_; }  // offsets lie in [-support, support]

    // Filter splatting with importance-sampled offsets. Sample s is drawn
    // with every pixel's point jittered by the same offset o ~ f (the
    // filter's density, above; the projection moves by +o, so pixel q sees
    // the point q + 0.5 - o). Pixel p's estimate from it is
    //     E_p = sum_d a_d(o) L(p + d + 0.5 - o),  a_d(o) = f(d - o) / F(-o),
    // F(x) = sum_k f(x + k), the density folded onto one pixel: the weighted
    // neighbours' own samples, nine at Blender's default width. Unbiased:
    // E_o[E_p] = sum_d int f(o) f(d - o) / F(-o) L(p + 0.5 + d - o) do, and
    // with x = d - o, F(-o) = F(x - d) = F(x), sum_d f(x - d) = F(x), so
    // E_o[E_p] = int f(x) L(p + 0.5 + x) dx, Cycles' filtered pixel, the
    // same as the pixel's own sample alone (weight 1; Cycles' estimator). The
    // weights sum to 1 per axis. Why: a small, very bright feature that only
    // the filter's tail reaches is hit by a pixel's own jitter with the
    // tail's small probability and then counts fully (a firefly, as in
    // Cycles); here it is seen by a neighbour's sample each time one lands
    // on it and counts with the tail's weight (issue 15's box_room, beside
    // the chrome ball's highlight).
    // The taps for offset o (the jitter, pixels) on one axis.
    SplatTaps splat_taps(float offset) const;
    // The farthest tap for any offset, pixels: a pixel nearer than this to
    // the image's edge keeps its own sample (its estimator may not depend on
    // o, or it would be biased). 0 (a filter half a pixel wide or
    // narrower, or one wider than the taps reach): no splatting.
    int splat_margin() const;
    // The same for Blender's filter width, without building the filter.
    static int splat_margin(float filter_width);

private:
    float half_width_;
    std::vector<float> inverse_cdf_;  // uniform in u
};

// The per-sample random numbers: a 4D R-sequence (Roberts 2018, generalised
// golden ratio), dimensions 0-1 for the pixel filter and 2-3 for the light
// shapes, so pixel jitter and light points are not correlated. Every
// dimension is shifted so that sample 0 sits at 0.5: sample 0 is the
// unjittered pixel centre, where Depth/Position/Index are taken, and looks
// at the centre of every light shape.
std::array<float, 4> sample_point(int sample);

// Sample `sample`'s point for the world's direction: the 2D R-sequence
// (alpha = 1/phi2, 1/phi2^2, phi2 = 1.32471... the plastic number), offset
// 0.5; its own sequence so the world's directions do not repeat the pixel
// jitter's or the light points' pattern.
std::array<float, 2> world_sample_point(int sample);

}  // namespace deferred

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

class PixelFilter {
public:
    // filter_width: Blender's render.filter_size (Cycles filter_width), pixels.
    explicit PixelFilter(float filter_width);
    // Inverse CDF of the 1D filter: u in [0,1) -> offset in pixels; u = 0.5 -> 0.
    float offset(float u) const;
    float support() const { return half_width_; }  // offsets lie in [-support, support]

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

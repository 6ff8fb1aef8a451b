#include "film.h"

#include <algorithm>
#include <cmath>

namespace deferred {

double blackman_harris(double v, double width) {
    const double x = 2.0 * M_PI * (v / width + 0.5);
    return 0.35875 - 0.48829 * std::cos(x) + 0.14128 * std::cos(2.0 * x) - 0.01168 * std::cos(3.0 * x);
}

PixelFilter::PixelFilter(float filter_width) {
    // Cycles: width *= 2 for Blackman-Harris, table over [-width/2, width/2].
    const double width = 2.0 * std::max(double(filter_width), 0.01);
    half_width_ = float(0.5 * width);
    constexpr int kSteps = 4096, kTable = 1024;
    std::vector<double> cdf(kSteps + 1, 0.0);
    for (int i = 0; i < kSteps; ++i) {
        const double x0 = -0.5 * width + width * i / kSteps, x1 = x0 + width / kSteps;
        cdf[i + 1] = cdf[i] + 0.5 * (blackman_harris(x0, width) + blackman_harris(x1, width)) * (x1 - x0);
    }
    for (double& c : cdf) c /= cdf.back();
    inverse_cdf_.resize(kTable + 1);
    for (int j = 0; j <= kTable; ++j) {
        const double u = double(j) / kTable;
        const auto it = std::lower_bound(cdf.begin(), cdf.end(), u);
        const int i = std::clamp(int(it - cdf.begin()), 1, kSteps);
        const double t = (u - cdf[i - 1]) / std::max(cdf[i] - cdf[i - 1], 1e-300);
        inverse_cdf_[j] = float(-0.5 * width + width * (i - 1 + std::clamp(t, 0.0, 1.0)) / kSteps);
    }
}

float PixelFilter::offset(float u) const {
    const float x = std::clamp(u, 0.0f, 1.0f) * float(inverse_cdf_.size() - 1);
    const int i = std::min(int(x), int(inverse_cdf_.size()) - 2);
    const float t = x - float(i);
    return inverse_cdf_[i] * (1.0f - t) + inverse_cdf_[i + 1] * t;
}

int PixelFilter::splat_margin(float filter_width) {
    // The support h is the filter width (Cycles doubles Blackman-Harris's).
    // Taps d with |d - o| < h for |o| <= h: |d| < 2h; at most ceil(2h) of
    // them are non-zero for one offset.
    const double h = std::max(double(filter_width), 0.01);
    if (!(h <= 0.5 * kMaxSplatTaps)) return 0;  // also NaN
    return std::max(int(std::ceil(2.0 * h)) - 1, 0);
}

int PixelFilter::splat_margin() const { return splat_margin(half_width_); }

SplatTaps PixelFilter::splat_taps(float offset) const {
    SplatTaps taps;
    const int margin = splat_margin();
    if (margin == 0) return taps;  // the pixel's own sample, weight 1
    const double h = double(half_width_), o = double(offset), width = 2.0 * h;
    // Every d in (o - h, o + h); f(d - o) as blackman_harris (the density's
    // constant cancels in the normalisation).
    const int first = std::max(int(std::floor(o - h)) + 1, -margin);
    const int last = std::min(int(std::ceil(o + h)) - 1, margin);
    taps.first = first;
    taps.count = 0;
    double sum = 0.0;
    std::array<double, kMaxSplatTaps> w{};
    for (int d = first; d <= last && taps.count < kMaxSplatTaps; ++d) {
        w[std::size_t(taps.count)] = std::max(blackman_harris(double(d) - o, width), 0.0);
        sum += w[std::size_t(taps.count++)];
    }
    if (taps.count == 0 || !(sum > 0.0)) return SplatTaps{};
    for (int k = 0; k < taps.count; ++k) taps.weight[std::size_t(k)] = float(w[std::size_t(k)] / sum);
    return taps;
}

std::array<float, 4> sample_point(int sample) {
    // alpha_i = phi^-i, phi = 1.16730... the real root of x^5 = x + 1.
    static constexpr double alpha[4] = {0.8566748838545029, 0.733891856627126, 0.6287067210378086,
                                        0.53859725722361};
    const double s = double(sample);
    std::array<float, 4> u;
    for (int i = 0; i < 4; ++i) u[std::size_t(i)] = float(std::fmod(0.5 + s * alpha[i], 1.0));
    return u;
}

std::array<float, 2> world_sample_point(int sample) {
    static constexpr double alpha[2] = {0.7548776662466927, 0.5698402909980532};
    const double s = double(sample);
    return {float(std::fmod(0.5 + s * alpha[0], 1.0)), float(std::fmod(0.5 + s * alpha[1], 1.0))};
}

}  // namespace deferred

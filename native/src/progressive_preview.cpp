#include "progressive_preview.h"

#include "gl_util.h"

namespace deferred {

void ProgressivePreview::begin(int width, int height, int total, int interval_ms) {
    width_ = width;
    height_ = height;
    total_ = total;
    interval_ms_ = interval_ms;
    last_publish_ = std::chrono::steady_clock::now();
    if (interval_ms < 0) return;
    std::lock_guard<std::mutex> lock(mutex_);
    // The previous render's image is stale (another view, another scene):
    // nothing until this render's first sample.
    image_ = PreviewImage();
    image_.version = next_version_++;
    image_.samples_total = total;
    image_.width = width;
    image_.height = height;
}

void ProgressivePreview::publish(GLuint image, int done, bool averaged, int channels) {
    if (interval_ms_ < 0) return;
    const auto now = std::chrono::steady_clock::now();
    const bool last = done >= total_;
    const bool first = done == 1;
    if (!last && !first && now - last_publish_ < std::chrono::milliseconds(interval_ms_)) return;
    last_publish_ = now;
    const std::size_t floats = std::size_t(width_) * std::size_t(height_) * 4;
    staging_.resize(floats);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(image, 0, GL_RGBA, GL_FLOAT, GLsizei(floats * sizeof(float)), staging_.data());
    check_gl("reading the progressive preview");
    const float scale = averaged ? float(total_) / float(done) : 1.0f;
    for (std::size_t i = 0; i < floats; i += 4) {
        float* p = &staging_[i];
        for (int c = 0; c < 4; ++c) p[c] *= scale;
        if (channels == 1) p[1] = p[2] = p[0];
        if (channels < 4) p[3] = 1.0f;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    image_.version = next_version_++;
    image_.samples_done = done;
    image_.samples_total = total_;
    image_.width = width_;
    image_.height = height_;
    image_.pixels.swap(staging_);
}

bool ProgressivePreview::take(std::uint64_t since, PreviewImage& out) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (image_.version <= since) return false;
    out = image_;
    return true;
}

}  // namespace deferred

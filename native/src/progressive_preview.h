// The newest accumulated Combined of a render in progress, for the 3D
// viewport (addon engine/viewport.py): the render thread publishes the film
// now and then while it samples, and the UI thread takes the newest image
// without waiting for the render (no call through the render thread).
#pragma once

#include <deferred/renderer.h>

#include <epoxy/gl.h>

#include <chrono>
#include <cstdint>
#include <mutex>

namespace deferred {

class ProgressivePreview {
public:
    // Render thread, before the first sample: a new render of `total`
    // samples; `interval_ms` < 0 turns publishing off for it.
    void begin(int width, int height, int total, int interval_ms);
    // Render thread, after `done` samples (1..total): reads `image` back
    // when the interval has passed since the last image, and always after
    // the first and the last sample. An `averaged` image (the film, the
    // filtered passes) holds sum(sample) / total; the preview holds
    // sum(sample) / done, the estimate of the finished pixel; others (the
    // passes of the first sample) are shown as they are. `channels` < 4:
    // the pass's channels, the rest filled as a display expects (one
    // channel grey, alpha 1).
    void publish(GLuint image, int done, bool averaged = true, int channels = 4);
    // Any thread: copies the newest image into `out` if its version is newer
    // than `since`; false otherwise.
    bool take(std::uint64_t since, PreviewImage& out) const;

private:
    mutable std::mutex mutex_;
    PreviewImage image_;  // guarded by mutex_
    std::uint64_t next_version_ = 1;
    // Render thread only.
    int width_ = 0, height_ = 0, total_ = 0, interval_ms_ = -1;
    std::chrono::steady_clock::time_point last_publish_;
    std::vector<float> staging_;
};

}  // namespace deferred

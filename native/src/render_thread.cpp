#include "render_thread.h"

#include <pthread.h>

namespace deferred {

RenderThread::RenderThread() : thread_([this] { loop(); }) {}

RenderThread::~RenderThread() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    cv_.notify_one();
    thread_.join();
}

void RenderThread::post(std::function<void()> job) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        jobs_.push_back(std::move(job));
    }
    cv_.notify_one();
}

void RenderThread::loop() {
    // Named for top -H, perf and bench/cpu/thread_load.py. Threads the GL
    // driver starts from here inherit the name unless they set their own
    // (llvmpipe's rasteriser threads are "llvmpipe-N"; its compute pool,
    // started with the EGL display, keeps this one): the render thread is
    // the first of them.
    pthread_setname_np(pthread_self(), "deferred-gl");
    for (;;) {
        std::function<void()> job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            cv_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
            if (jobs_.empty()) return;  // stopping and drained
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        job();  // packaged_task stores exceptions in its future
    }
}

}  // namespace deferred

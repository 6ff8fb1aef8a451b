// The one thread that owns the GL context. Every GL call of the library runs
// here; callers submit closures and wait for them, so they never need (or
// disturb) a current context of their own (Blender keeps its own GL contexts
// on its threads, and with libglvnd a thread cannot hold two APIs at once).
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <future>
#include <mutex>
#include <thread>

namespace deferred {

class RenderThread {
public:
    RenderThread();
    ~RenderThread();  // finishes queued work, then joins
    RenderThread(const RenderThread&) = delete;
    RenderThread& operator=(const RenderThread&) = delete;

    // Runs `fn` on the render thread and waits; exceptions thrown there are
    // rethrown in the caller.
    template <class Fn>
    auto run(Fn&& fn) -> decltype(fn()) {
        using R = decltype(fn());
        std::packaged_task<R()> task(std::forward<Fn>(fn));
        std::future<R> result = task.get_future();
        post([&task] { task(); });
        return result.get();
    }

private:
    void post(std::function<void()> job);
    void loop();

    std::mutex mutex_;
    std::condition_variable cv_;
    std::deque<std::function<void()>> jobs_;
    bool stopping_ = false;
    std::thread thread_;
};

}  // namespace deferred

// Plain CPU work split over the machine's cores: readback's copies into
// newly allocated images, whose cost is mostly the kernel's first-touch page
// faults (about 2 GB/s on one core; 340 MB of 16 passes at 1080p took 171 ms
// of an H200 frame in one thread), and faults on different pages proceed
// in parallel. No GL in `work`: only the render thread has the context.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace deferred {

// Memory-bound copies gain little beyond this many threads, and a 128-core
// server would otherwise start a thread per Cryptomatte chunk.
constexpr std::size_t kMaxParallelThreads = 16;

// work(i) for each i in [0, count), on up to hardware_concurrency threads
// (at most kMaxParallelThreads, this one included), each taking the next
// index as it finishes; rethrows the first exception after all have ended.
// Where no thread can be started, this one does it all.
template <typename Work>
void parallel_for(std::size_t count, const Work& work) {
    const std::size_t threads = std::min<std::size_t>(
        {count, std::size_t(std::max(1u, std::thread::hardware_concurrency())), kMaxParallelThreads});
    std::atomic<std::size_t> next{0};
    std::mutex error_lock;
    std::exception_ptr error;
    auto run = [&] {
        for (std::size_t i; (i = next.fetch_add(1)) < count;) {
            try {
                work(i);
            } catch (...) {
                std::lock_guard<std::mutex> hold(error_lock);
                if (!error) error = std::current_exception();
            }
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(threads);  // emplace_back below cannot throw bad_alloc with threads running
    try {
        for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(run);
    } catch (const std::system_error&) {
        // No more threads: the ones started and this one take the rest.
    }
    run();
    for (std::thread& th : pool) th.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace deferred

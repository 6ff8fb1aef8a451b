#include "cpu_rasteriser.h"

#include <dlfcn.h>
#include <sys/types.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace deferred {

bool is_cpu_rasteriser(const std::string& gl_renderer) {
    return gl_renderer.find("llvmpipe") != std::string::npos || gl_renderer.find("softpipe") != std::string::npos;
}

void keep_freed_memory_at_heap_tops(int megabytes) {
    static std::once_flag once;
    std::call_once(once, [megabytes] {
        int mb = megabytes;
        if (const char* env = std::getenv("DEFERRED_MALLOC_TOP_PAD_MB")) mb = std::atoi(env);
        if (mb <= 0) return;
#if defined(__GLIBC__)
        mallopt(M_TOP_PAD, std::min(mb, 1024) << 20);  // M_TOP_PAD is an int of bytes
#endif
    });
}

std::string jemalloc_note() {
    // mallctl is jemalloc's own entry point: absent, another allocator runs.
    using Mallctl = int (*)(const char*, void*, std::size_t*, void*, std::size_t);
    const auto mallctl = reinterpret_cast<Mallctl>(dlsym(RTLD_DEFAULT, "mallctl"));
    if (!mallctl) return "";
    std::size_t fit = 0, fit_size = sizeof(fit);
    ssize_t muzzy = 0;
    std::size_t muzzy_size = sizeof(muzzy);
    if (mallctl("opt.lg_extent_max_active_fit", &fit, &fit_size, nullptr, 0) != 0 ||
        mallctl("opt.muzzy_decay_ms", &muzzy, &muzzy_size, nullptr, 0) != 0)
        return "";
    if (fit >= 20 && muzzy < 0) return "";
    return std::string("this process allocates with jemalloc, which returns the CPU rasteriser's freed memory to the "
                       "system and faults it in again for every shadow map and sample; start Blender with MALLOC_CONF=") +
           kJemallocConf + " for renders up to 4x faster (README, \"Rendering on the CPU\")";
}

}  // namespace deferred

// What Mesa's CPU rasterisers (llvmpipe, softpipe) ask of the process that
// renders with them.
#pragma once

#include <string>

namespace deferred {

// Whether GL_RENDERER names one of Mesa's CPU rasterisers.
bool is_cpu_rasteriser(const std::string& gl_renderer);

// llvmpipe bins every draw's triangles into memory blocks it allocates and
// frees again for each scene it rasterises; glibc returns the freed top of
// each heap to the system (beyond M_TOP_PAD, 128 KiB by default), so the
// next scene faults the same pages in again, zeroed by the kernel. The
// instancing capture (10 000 rocks, 44 shadow layers; 320x180, 4 samples,
// three renders) took 416 000-437 000 page faults, its renders 2.7-3.8 s
// and their shadow maps 2.2-3.0 s; with 32 MiB kept at the top of each
// heap, 87 000-136 000 faults, 1.6-2.3 s and 1.1-1.7 s (README, "Rendering
// on the CPU").
// Raises M_TOP_PAD to `megabytes`, at most 1024 (DEFERRED_MALLOC_TOP_PAD_MB overrides;
// 0 leaves glibc's setting), once per process; the cost is up to that much
// freed memory each heap keeps. No-op without glibc.
void keep_freed_memory_at_heap_tops(int megabytes = 32);

// jemalloc, where it is the process's allocator (Blender links it), does
// the same with its defaults, and cannot be told otherwise once running:
// its options are read at start-up from MALLOC_CONF. In Blender 3.4 on
// llvmpipe the instancing sample's 4-sample render took 7.5-9.6 s with the
// defaults (1.46 M page faults over three renders) and 2.1-3.1 s with
// kJemallocConf (0.15 M; bench/cpu/bench_malloc_conf.py): freed pages stay mapped, marked MADV_FREE for
// the kernel to take back only under memory pressure (muzzy_decay_ms -1),
// and a freed extent serves requests up to 2^20 times smaller than itself
// (lg_extent_max_active_fit 20, default 6) instead of fresh pages; either
// alone left 0.3-0.9 M faults and 5-6 s in the replay run under jemalloc.
// Returns a note naming the setting where jemalloc runs without it, else "".
constexpr const char* kJemallocConf = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20";
std::string jemalloc_note();

}  // namespace deferred

#!/usr/bin/env bash
# Configure, build and run every test (C++ GoogleTest + Blender tests) via CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
# Blender allocates with jemalloc, whose defaults make llvmpipe fault its
# freed memory in again for every draw batch (native/src/cpu_rasteriser.h).
export MALLOC_CONF=${MALLOC_CONF:-muzzy_decay_ms:-1,lg_extent_max_active_fit:20}
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2

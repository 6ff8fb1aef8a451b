#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run of the robustness suite
# (issue 7): builds build-asan/ with -DDEFERRED_SANITIZE=ON (our code
# instrumented, the GL driver not) and runs, through CTest (label robustness):
#   robustness.Validation.*  scene/camera validation, no GL (random bit patterns,
#                            exact-size heap arrays: any over-read is reported)
#   robustness_fuzz          random scenes through the native API on llvmpipe
#                            (DEFERRED_FUZZ_SCENES, default 300 here)
#   robustness.HardCases.*, robustness.BsdfExtremes.*
# Any sanitizer report aborts the test, so a clean run prints
# "100% tests passed". About 3 minutes on 2 cores once built (the first run
# compiles the shader variants; Mesa caches them on disk).
#
#   bash scripts/sanitize.sh            # build + run
#   BUILD_DIR=/tmp/asan bash scripts/sanitize.sh
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD_DIR:-$ROOT/build-asan}
JOBS=${JOBS:-$(nproc)}

cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDEFERRED_SANITIZE=ON -DDEFERRED_BUILD_PYTHON=OFF
cmake --build "$BUILD" -j"$JOBS" --target robustness_validation robustness_fuzz robustness_gl_tests

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export DEFERRED_FUZZ_SCENES=${DEFERRED_FUZZ_SCENES:-300}
ctest --test-dir "$BUILD" -L robustness --output-on-failure

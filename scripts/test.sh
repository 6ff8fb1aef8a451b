#!/usr/bin/env bash
# Configure, build and run every test (C++ GoogleTest + Blender tests) via CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2

#!/usr/bin/env bash
# The main job: set up, build, and render a sample scene with the Deferred
# engine through real Blender, headless. Writes out/<scene>.exr (every pass,
# multilayer) and out/<scene>.png (Combined preview, one render).
# Usage: scripts/render_sample.sh [scene, default showcase]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-showcase}
# Blender allocates with jemalloc, whose defaults make llvmpipe fault its
# freed memory in again for every draw batch (native/src/cpu_rasteriser.h).
export MALLOC_CONF=${MALLOC_CONF:-muzzy_decay_ms:-1,lg_extent_max_active_fit:20}
bash scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
BLENDER_USER_SCRIPTS="$PWD/build/blender_scripts" blender -b --factory-startup "blend_samples/$scene.blend" \
  --addons deferred_render -E DEFERRED_RENDER --python-exit-code 1 \
  --python blend_samples/render_sample.py -- "out/$scene"

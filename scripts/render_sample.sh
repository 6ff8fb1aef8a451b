#!/usr/bin/env bash
# The main job: set up, build, and render a sample scene with the Deferred
# engine through real Blender, headless. Writes out/<scene>_0001.exr (every
# pass, multilayer) and out/<scene>.png (Combined preview).
# Usage: scripts/render_sample.sh [scene, default showcase]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-showcase}
bash scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
mkdir -p out
BLENDER_USER_SCRIPTS="$PWD/build/blender_scripts" blender -b "blend_samples/$scene.blend" \
  --python-exit-code 1 --addons deferred_render -E DEFERRED_RENDER \
  -o "$PWD/out/${scene}_" -F OPEN_EXR_MULTILAYER -f 1
/usr/bin/python3.11 scripts/exr_to_png.py "out/${scene}_0001.exr" "out/${scene}.png"

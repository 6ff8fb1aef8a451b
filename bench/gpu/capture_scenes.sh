#!/usr/bin/env bash
# Re-captures the benchmark scenes (bench/gpu/captures/*.npz) from the
# sample .blend files through Blender (DEFERRED_RENDER_CAPTURE): run after a
# change of the native API makes the committed captures stale (the test
# replay_bench_captures says so). Needs a build (build/blender_scripts).
#   bash bench/gpu/capture_scenes.sh [build_dir]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$repo/build}"
for scene in box_room many_lights showcase instancing transparency emitters; do
  DEFERRED_RENDER_CAPTURE="$repo/bench/gpu/captures/$scene.npz" \
  BLENDER_USER_SCRIPTS="$build/blender_scripts" \
    blender -b --factory-startup --addons deferred_render "$repo/blend_samples/$scene.blend" \
      -E DEFERRED_RENDER --python-exit-code 1 \
      --python-expr "import bpy; s = bpy.context.scene; s.render.resolution_percentage = 10; s.deferred_render.samples = 1; bpy.ops.render.render()" \
    | grep -E "captured|Error" || true
  test -f "$repo/bench/gpu/captures/$scene.npz"
done
# The node-materials scene (constant and textured materials).
BLENDER_USER_SCRIPTS="$build/blender_scripts" \
  blender -b --factory-startup --addons deferred_render -E DEFERRED_RENDER --python-exit-code 1 \
    --python "$repo/bench/gpu/capture_materials.py" | grep -E "captured|Error" || true

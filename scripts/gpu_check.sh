#!/usr/bin/env bash
# The GPU check, run on a lent GPU machine over the binaries that
# scripts/gpu_stage.sh put in .gpu/: the native and robustness tests on the
# GPU's driver, then the benchmarks behind issue 12's targets at 1920x1080
# (frame stages, 64 samples end to end, the 16 passes' readback and a warm
# render's time before its first sample: deferred_bench_frame; 1 000 /
# 10 000 lights: deferred_bench_lights; the outputs' cost:
# deferred_bench_outputs; shadows: deferred_bench_shadows). Writes four
# files to $OUT (the device tool returns at most eight): summary.txt,
# native_tests.log, robustness.log, benches.md. Each step has a time limit
# (killed 5 s after it); the limits add up to 500 s, inside one device call
# (600 s). Exits non-zero when a step failed or ran out of time.
#   bash scripts/gpu_check.sh            (on the device, as root)
#   GPU_CHECK_LOCAL=1 GPU_CHECK_SIZE="320 180" OUT=/tmp/gpu bash scripts/gpu_check.sh   (a dry run here)
set -u
cd "$(dirname "$0")/.." || exit 1
out="${OUT:-/tmp/gpu_check}"
mkdir -p "$out"
stage="$PWD/.gpu"
test -x "$stage/bin/deferred_native_tests" || { echo "no .gpu/: run scripts/gpu_stage.sh here first, carry .gpu" >&2; exit 1; }
if [ -z "${GPU_CHECK_LOCAL:-}" ]; then
  # The GL loaders over / (the device README's recipe), the NVIDIA vendor files.
  for f in "$stage"/debs/*.deb; do
    [ -f "$f" ] && dpkg -x "$f" /
  done
  ldconfig
  for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json /usr/share/glvnd/egl_vendor.d/10_nvidia.json; do
    if [ -f "$f" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$f"; break; fi
  done
fi
export LD_LIBRARY_PATH="$stage/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
size="${GPU_CHECK_SIZE:-1920 1080}"
summary="$out/summary.txt"
benches="$out/benches.md"
: > "$out/native_tests.log"
: > "$out/robustness.log"
: > "$benches"
{
  echo "staged from $(cat "$stage/commit" 2>/dev/null), run at $(date -u +%FT%TZ)"
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1 || echo "(no nvidia-smi)"
} > "$summary"
failed=0
run() {  # run NAME SECONDS LOG COMMAND...: time-limited; its exit status and time go to the summary
  local name="$1" limit="$2" log="$3"; shift 3
  local t0=$SECONDS
  timeout -k 5 "$limit" "$@" >> "$log" 2>&1
  local rc=$?
  local note=""
  case "$rc" in 0) ;; 124|137) failed=1; note=" (time limit)" ;; *) failed=1 ;; esac
  echo "$name: exit $rc$note in $((SECONDS - t0)) s" >> "$summary"
}
run native_tests 160 "$out/native_tests.log" "$stage/bin/deferred_native_tests"
run robustness_gl_tests 80 "$out/robustness.log" "$stage/bin/robustness_gl_tests"
grep -h -E '^\[  (PASSED|FAILED) ' "$out/native_tests.log" "$out/robustness.log" >> "$summary"
# shellcheck disable=SC2086
run bench_frame 60 "$benches" "$stage/bin/deferred_bench_frame" $size
# Brute force (every light at every pixel) up to 1000 lights, beside the culled rows up to 65 536.
# shellcheck disable=SC2086
run bench_lights 90 "$benches" "$stage/bin/deferred_bench_lights" $size 1000
# shellcheck disable=SC2086
run bench_outputs 55 "$benches" "$stage/bin/deferred_bench_outputs" $size
# shellcheck disable=SC2086
run bench_shadows 55 "$benches" "$stage/bin/deferred_bench_shadows" $size
cat "$summary"
exit "$failed"

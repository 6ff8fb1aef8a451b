#!/usr/bin/env bash
# The GPU check, run on a lent GPU machine over the binaries that
# scripts/gpu_stage.sh put in .gpu/: the native and robustness tests on the
# GPU's driver, then the benchmarks behind issue 12's targets at 1920x1080
# (frame stages, 64 samples end to end, the 16 passes' readback and a warm
# render's time before its first sample: deferred_bench_frame; 1 000 /
# 10 000 lights: deferred_bench_lights; the outputs' cost:
# deferred_bench_outputs; shadows: deferred_bench_shadows; node materials'
# geometry pass against constant ones: deferred_bench_materials; the raster
# pipeline against compute on this GPU: deferred_bench_raster; shadow rays'
# compile time against the traversal's call sites: deferred_bench_ray_compile).
# Writes four
# files to $OUT (the device tool returns at most eight): summary.txt,
# native_tests.log, robustness.log, benches.md. Each step has a time limit
# (killed 5 s after it): 100 s for the tests (in parallel), 430 s for the
# benchmarks (with the kills' grace and the loaders' setup, under 600 s: one
# device call with timeout_s=600) inside a session's 15 minutes of device
# time. Exits non-zero when a step failed or ran out of time.
# Parts of it, for a rerun inside what is left of the device time:
# GPU_CHECK_FILTER (a gtest filter for both test binaries, "-" for no
# tests), GPU_CHECK_TEST_LIMIT (seconds, 100), GPU_CHECK_BENCHES (any of
# "raster materials raycompile frame lights outputs shadows", all by
# default; DEFERRED_BENCH_FRAME_BLOCKS=rays runs the frame bench's
# shadow-rays block alone).
#   bash scripts/gpu_check.sh            (on the device, as root)
#   GPU_CHECK_FILTER='HardCases.*' GPU_CHECK_BENCHES=frame bash scripts/gpu_check.sh
#   GPU_CHECK_LOCAL=1 GPU_CHECK_SIZE="160 90" OUT=/tmp/gpu bash scripts/gpu_check.sh   (a dry run here)
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
# The tests in parallel: 8 shards of the native tests beside the robustness
# tests (their first NVIDIA run, serial, ran out of its limit: most of a
# test's time there is the driver compiling programs, on the CPU).
# Line-buffered, so a test stopped at the limit leaves its last lines.
filter="${GPU_CHECK_FILTER:-*}"
test_limit="${GPU_CHECK_TEST_LIMIT:-100}"
benches_to_run=" ${GPU_CHECK_BENCHES:-raster materials raycompile frame lights outputs shadows} "
if [ "$filter" != "-" ]; then
t0=$SECONDS
shards=8
pids=()
for i in $(seq 0 $((shards - 1))); do
  GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i timeout -k 5 "$test_limit" stdbuf -oL -eL \
    "$stage/bin/deferred_native_tests" --gtest_filter="$filter" > "$out/native_shard_$i.tmp" 2>&1 &
  pids+=($!)
done
timeout -k 5 "$test_limit" stdbuf -oL -eL "$stage/bin/robustness_gl_tests" --gtest_filter="$filter" \
  > "$out/robustness.log" 2>&1 &
rpid=$!
for i in $(seq 0 $((shards - 1))); do
  wait "${pids[$i]}"
  rc=$?
  [ "$rc" = 0 ] || failed=1
  echo "native_tests shard $i: exit $rc$(case $rc in 124|137) echo ' (time limit)';; esac)" >> "$summary"
  { echo "=== shard $i of $shards: exit $rc"; cat "$out/native_shard_$i.tmp"; } >> "$out/native_tests.log"
  rm -f "$out/native_shard_$i.tmp"
done
wait "$rpid"
rc=$?
[ "$rc" = 0 ] || failed=1
echo "robustness_gl_tests: exit $rc; the tests took $((SECONDS - t0)) s" >> "$summary"
grep -h -E '^\[  (PASSED|FAILED) ' "$out/native_tests.log" "$out/robustness.log" >> "$summary"
# A test still running when its shard was stopped: the shard's last RUN line
# (the robustness tests' log is not read: it is one process, stopped or not).
for i in $(seq 0 $((shards - 1))); do
  awk -v s="$i" '/^=== shard/ {n=$3} n==s && /^\[ RUN/ {r=$0} n==s && /^\[ *(OK|FAILED|SKIPPED) / {r=""} END {if (r != "") print "unfinished in shard " s ": " r}' \
    "$out/native_tests.log" >> "$summary"
done
fi
# The benchmarks one at a time (timings), with a CPU profile of the frames
# (DEFERRED_BENCH_PROFILE: bench/cpu_profile.h) where the engine's GPU
# timestamps cannot tell GPU work from the CPU issuing it.
export DEFERRED_BENCH_PROFILE=1
# The cheap ones first, so a check stopped early still has them.
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" raster "* ]] && run bench_raster 30 "$benches" "$stage/bin/deferred_bench_raster" $size
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" materials "* ]] && run bench_materials 100 "$benches" "$stage/bin/deferred_bench_materials" $size 16 3
[[ "$benches_to_run" == *" raycompile "* ]] && run bench_ray_compile 50 "$benches" "$stage/bin/deferred_bench_ray_compile" 16
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" frame "* ]] && run bench_frame 100 "$benches" stdbuf -oL "$stage/bin/deferred_bench_frame" $size
# Brute force (every light at every pixel) up to 1000 lights, beside the culled rows up to 65 536.
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" lights "* ]] && run bench_lights 40 "$benches" "$stage/bin/deferred_bench_lights" $size 1000
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" outputs "* ]] && run bench_outputs 60 "$benches" "$stage/bin/deferred_bench_outputs" $size
# shellcheck disable=SC2086
[[ "$benches_to_run" == *" shadows "* ]] && run bench_shadows 50 "$benches" stdbuf -oL "$stage/bin/deferred_bench_shadows" $size
cat "$summary"
exit "$failed"

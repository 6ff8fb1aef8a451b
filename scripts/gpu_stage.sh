#!/usr/bin/env bash
# Stages what the GPU check (scripts/gpu_check.sh) needs on a lent GPU
# machine (the tool library's `device`), which has no Debian packages and no
# network: the native test and benchmark binaries built here (C++ only, so
# the device's own Python does not matter), the one shared library they
# need beyond libc and libstdc++ (libepoxy, which opens the driver's EGL),
# and the GL loader packages the device's README asks for (glvnd's libEGL,
# libGL, ...). Everything goes to .gpu/ (ignored through .git/info/exclude).
# Then, with the device tool:
#   run(command="bash scripts/gpu_check.sh", carry=[".gpu"], timeout_s=600)
# and commit what comes back (the GPU's name is in it) into bench/gpu/results/.
#   bash scripts/gpu_stage.sh [build_dir]
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$repo/build}"
stage="$repo/.gpu"
binaries="tests/deferred_native_tests tests/robustness/robustness_gl_tests bench/deferred_bench_frame
          bench/deferred_bench_lights bench/deferred_bench_outputs bench/deferred_bench_shadows
          bench/deferred_bench_materials bench/deferred_bench_raster
          bench/deferred_bench_ray_compile"
for b in $binaries; do
  test -x "$build/$b" || { echo "missing $build/$b: build first (cmake --build $build)" >&2; exit 1; }
done
exclude="$(git -C "$repo" rev-parse --git-path info/exclude)"
case "$exclude" in /*) ;; *) exclude="$repo/$exclude" ;; esac
mkdir -p "$(dirname "$exclude")"
grep -qx '/.gpu/' "$exclude" 2>/dev/null || echo '/.gpu/' >> "$exclude"
rm -rf "$stage"
mkdir -p "$stage/bin" "$stage/lib" "$stage/debs"
for b in $binaries; do cp "$build/$b" "$stage/bin/"; done
# libepoxy (the GL loader the library links); the rest of the dependencies
# are libc, libm, libstdc++ and libgcc, which the device's newer system has.
epoxy="$(ldd "$stage/bin/deferred_native_tests" | awk '/libepoxy/ {print $3}')"
cp -L "$epoxy" "$stage/lib/"
unexpected="$(ldd "$stage/bin/"* | awk '/=>/ {print $1}' | sort -u |
  grep -v -E '^(libepoxy|libstdc\+\+|libm|libgcc_s|libc|libdl|libpthread|librt|linux-vdso)\.so' || true)"
if [ -n "$unexpected" ]; then echo "unexpected shared libraries (stage them too): $unexpected" >&2; exit 1; fi
# The GL loaders (device README): unpacked over / there, not here.
(cd "$stage/debs" && apt-get download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null)
# The tree the binaries were staged from (build them from it: the script cannot tell).
git -C "$repo" describe --always --dirty > "$stage/commit"
du -sh "$stage"

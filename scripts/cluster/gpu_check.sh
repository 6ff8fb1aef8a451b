#!/usr/bin/env bash
# On a machine with NVIDIA GPUs: checks that each process renders on the GPU
# CUDA_VISIBLE_DEVICES names (for every GPU, the EGL device the engine picks
# has the UUID nvidia-smi gives that index), then measures frames per hour
# one process against one process per GPU (and a local Slurm array when the
# packages are there), writing bench/farm/results/<gpu>.md.
#
#   bash scripts/cluster/gpu_check.sh        (after scripts/test.sh's build)
#
# nvidia-smi numbers GPUs by PCI bus; CUDA_DEVICE_ORDER=PCI_BUS_ID makes CUDA
# do the same, so that index i means one GPU to both.
set -euo pipefail
cd "$(dirname "$0")/../.."
command -v nvidia-smi >/dev/null || { echo "gpu_check.sh: no nvidia-smi: not an NVIDIA machine" >&2; exit 2; }
export CUDA_DEVICE_ORDER=PCI_BUS_ID
for i in $(nvidia-smi --query-gpu=index --format=csv,noheader); do
  uuid=$(nvidia-smi -i "$i" --query-gpu=uuid --format=csv,noheader)
  echo "== CUDA_VISIBLE_DEVICES=$i ($uuid)"
  CUDA_VISIBLE_DEVICES=$i DEFERRED_EXPECT_GPU_UUID=$uuid \
    build/tests/deferred_native_tests --gtest_filter='DeviceSelection.*:Context.*'
done
echo "== CUDA_VISIBLE_DEVICES='' (must be a clear error)"
if CUDA_VISIBLE_DEVICES= build/tests/deferred_native_tests --gtest_filter='DeviceSelection.ThisMachine' 2>&1 |
    tee /dev/stderr | grep -q "leaves this process no GPU"; then
  echo "ok: an empty CUDA_VISIBLE_DEVICES is refused with a clear error"
else
  echo "FAIL: an empty CUDA_VISIBLE_DEVICES was not refused" >&2
  exit 1
fi
name=$(nvidia-smi -i 0 --query-gpu=name --format=csv,noheader | tr ' ' '_')
BENCH_SLURM=${BENCH_SLURM:-1} /usr/bin/python3 bench/farm/bench_farm.py --out "bench/farm/results/$name.md"

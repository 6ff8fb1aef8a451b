#!/usr/bin/env bash
# Renders a frame range across the GPUs of one machine, without a scheduler:
# one Blender process per GPU, each seeing only its GPU through
# CUDA_VISIBLE_DEVICES (the engine renders on the GPU CUDA calls 0 then),
# contiguous blocks of frames each; then the same summary as the Slurm path.
#
#   bash scripts/cluster/render_gpus.sh FILE.blend OUTDIR START END [GPUS]
#
# GPUS: comma-separated CUDA device indices; default every GPU nvidia-smi
# lists (within CUDA_VISIBLE_DEVICES if that is set), or one process on the
# default device where there is no NVIDIA GPU. Resumable like slurm_render.sh:
# frames already on disk are skipped. Exit status is the summary's (0 when
# every frame exists).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if [ $# -lt 4 ] || [ $# -gt 5 ]; then
  echo "usage: $0 FILE.blend OUTDIR START END [GPUS]" >&2
  exit 2
fi
blend="$(realpath -e "$1")"
out="$(realpath -m "$2")"
start=$3 end=$4
gpus=${5:-}
if [ -z "$gpus" ]; then
  if [ -n "${CUDA_VISIBLE_DEVICES:-}" ]; then
    gpus=$CUDA_VISIBLE_DEVICES
  elif command -v nvidia-smi >/dev/null && nvidia-smi -L >/dev/null 2>&1; then
    gpus=$(nvidia-smi --query-gpu=index --format=csv,noheader | paste -sd, -)
  fi
fi
IFS=, read -r -a gpu_list <<< "${gpus:-}"
count=${#gpu_list[@]}
[ "$count" -ge 1 ] || count=1
frames=$(( end - start + 1 ))
[ "$frames" -ge 1 ] || { echo "render_gpus.sh: START $start is after END $end" >&2; exit 2; }
per_task=$(( (frames + count - 1) / count ))
mkdir -p "$out/.deferred_farm/logs"
submitted=$(date +%s.%N)
pids=()
for (( i = 0; i < count; i++ )); do
  log="$out/.deferred_farm/logs/gpu-$i.out"
  if [ -n "${gpu_list[$i]:-}" ]; then
    echo "GPU ${gpu_list[$i]}: task $i, log $log"
    CUDA_VISIBLE_DEVICES="${gpu_list[$i]}" FARM_TASK_NAME="gpu${gpu_list[$i]}-$$" \
      bash "$here/render_task.sh" "$blend" "$out" "$start" "$end" "$per_task" "$i" > "$log" 2>&1 &
  else
    echo "default device: task $i, log $log"
    FARM_TASK_NAME="local-$$" bash "$here/render_task.sh" "$blend" "$out" "$start" "$end" "$per_task" "$i" \
      > "$log" 2>&1 &
  fi
  pids+=($!)
done
failed=0
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
[ "$failed" -eq 0 ] || echo "render_gpus.sh: a process failed; see $out/.deferred_farm/logs/" >&2
python3 "$here/farm_summary.py" "$out" "$start" "$end" --since "$submitted"

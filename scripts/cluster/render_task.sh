#!/usr/bin/env bash
# One farm task: renders frames FIRST..LAST of a .blend into OUTDIR with the
# Deferred engine, skipping frames already on disk (render_frames.py).
#
#   bash scripts/cluster/render_task.sh FILE.blend OUTDIR START END FRAMES_PER_TASK [TASK_INDEX]
#
# The task's frames are START + TASK_INDEX*FRAMES_PER_TASK onwards, at most
# FRAMES_PER_TASK of them and none past END. TASK_INDEX defaults to
# SLURM_ARRAY_TASK_ID, so the same script is a Slurm array task
# (slurm_render.sh), a process per GPU (render_gpus.sh), or one job of
# another farm manager (Flamenco, Deadline, a shell loop: see README).
#
# Environment: BLENDER (default blender); BLENDER_USER_SCRIPTS (default this
# checkout's build/blender_scripts, where the build puts the add-on);
# CUDA_VISIBLE_DEVICES picks the GPU (the scheduler sets it).
set -euo pipefail
# sbatch runs a copy of this script from its spool: DEFERRED_FARM_SCRIPTS
# (set by slurm_render.sh) names the checkout's scripts/cluster.
here="${DEFERRED_FARM_SCRIPTS:-$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)}"
repo="$(cd "$here/../.." && pwd)"
if [ $# -lt 5 ]; then
  echo "usage: $0 FILE.blend OUTDIR START END FRAMES_PER_TASK [TASK_INDEX]" >&2
  exit 2
fi
blend=$1 out=$2 start=$3 end=$4 per_task=$5
index=${6:-${SLURM_ARRAY_TASK_ID:-}}
if [ -z "$index" ]; then
  echo "render_task.sh: no TASK_INDEX given and SLURM_ARRAY_TASK_ID is not set" >&2
  exit 2
fi
first=$(( start + index * per_task ))
last=$(( first + per_task - 1 ))
if [ "$last" -gt "$end" ]; then last=$end; fi
if [ "$first" -gt "$end" ]; then
  echo "render_task.sh: task $index has no frames (first $first > end $end)"
  exit 0
fi
export BLENDER_USER_SCRIPTS="${BLENDER_USER_SCRIPTS:-$repo/build/blender_scripts}"
echo "render_task.sh: task $index frames $first..$last on $(hostname) CUDA_VISIBLE_DEVICES=${CUDA_VISIBLE_DEVICES-<unset>}"
# exec: the task's process is Blender itself, so that a signal the scheduler
# sends (scancel, time limit) reaches the renderer and not only this shell.
exec "${BLENDER:-blender}" -b --factory-startup "$blend" --addons deferred_render -E DEFERRED_RENDER \
  --python-exit-code 1 --python "$here/render_frames.py" -- \
  --output "$out/####" --frames "$first-$last" ${FARM_TASK_NAME:+--task "$FARM_TASK_NAME"}

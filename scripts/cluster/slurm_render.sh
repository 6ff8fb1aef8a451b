#!/usr/bin/env bash
# Renders a frame range of a .blend with the Deferred engine as a Slurm job
# array: FRAMES_PER_TASK frames per task, one GPU per task.
#
#   bash scripts/cluster/slurm_render.sh FILE.blend OUTDIR START END [FRAMES_PER_TASK]
#       submits the array and prints its job id (nothing to do: prints so, no id)
#   bash scripts/cluster/slurm_render.sh --wait JOBID
#       waits until the job has left the queue, then prints the summary:
#       every frame checked, per-frame time and GPU, frames per hour; exits
#       1 if frames are missing, naming them and the command to resubmit
#
# Frames are OUTDIR/#### with the extension of the .blend's output format
# (what `blender -o OUTDIR/####` writes). Resumable: frames already on disk
# are skipped, and a resubmission submits only the tasks that still miss
# frames; a frame is renamed onto its name only once it is completely
# written (render_frames.py), so a killed task never leaves a truncated
# frame behind.
#
# Environment:
#   GPUS_PER_TASK          GPUs per task (default 1; 0 on CPU-only nodes);
#                          Slurm sets CUDA_VISIBLE_DEVICES from --gres and
#                          the engine renders on that GPU
#   SLURM_RENDER_ARGS      more sbatch options, e.g. "--partition=gpu --time=2:00:00"
#   BLENDER, BLENDER_USER_SCRIPTS   as for render_task.sh
#   DEFERRED_FARM_STATE    where job manifests live (default ~/.cache/deferred_render/slurm)
# The .blend, OUTDIR and this checkout must be on a filesystem every node
# sees (the usual shared /home or /project of a cluster); sbatch's own
# SBATCH_* variables work as usual.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
state="${DEFERRED_FARM_STATE:-$HOME/.cache/deferred_render/slurm}"

die() { echo "slurm_render.sh: $*" >&2; exit 2; }
is_int() { [[ "$1" =~ ^-?[0-9]+$ ]]; }

wait_and_summarize() {
  local job=$1 manifest="$state/$1.env"
  [ -f "$manifest" ] || die "no manifest for job $job in $state (was it submitted from here?)"
  # shellcheck disable=SC1090
  source "$manifest"
  # Poll the queue: the job is done when none of its tasks is listed (a job
  # that has already aged out of slurmctld is done as well).
  while squeue -h -j "$job" -o %i 2>/dev/null | grep -q .; do
    sleep "${SLURM_RENDER_POLL_S:-2}"
  done
  echo "job $job has finished; $(basename "$BLEND") frames $START..$END in $OUTDIR"
  # Each task's end as slurmctld remembers it (MinJobAge; no accounting
  # database is needed): a killed or failed task is named here.
  scontrol -o show job "$job" 2>/dev/null | tr ' ' '\n' |
    awk -F= '$1=="ArrayTaskId"{t=$2} $1=="JobState"{s=$2} $1=="ExitCode"{e=$2}
             $1=="NodeList"{printf "task %s: %s (exit %s) on %s\n", t, s, e, $2}' || true
  if python3 "$here/farm_summary.py" "$OUTDIR" "$START" "$END" --since "$SUBMITTED" \
      --json "$OUTDIR/.deferred_farm/summary-$job.json"; then
    return 0
  fi
  echo "resubmit the missing frames with:"
  echo "  bash $here/slurm_render.sh $(printf '%q ' "$BLEND" "$OUTDIR" "$START" "$END" "$PER_TASK")"
  return 1
}

if [ "${1:-}" = "--wait" ]; then
  [ $# -eq 2 ] && is_int "$2" || die "usage: $0 --wait JOBID"
  wait_and_summarize "$2"
  exit $?
fi

[ $# -ge 4 ] && [ $# -le 5 ] || die "usage: $0 FILE.blend OUTDIR START END [FRAMES_PER_TASK] | --wait JOBID"
blend="$(realpath -e "$1" 2>/dev/null)" || die "no such .blend: $1"
out="$(realpath -m "$2")"
start=$3 end=$4 per_task=${5:-10}
is_int "$start" && is_int "$end" || die "START and END must be frame numbers"
[ "$start" -le "$end" ] || die "START $start is after END $end"
is_int "$per_task" && [ "$per_task" -ge 1 ] || die "FRAMES_PER_TASK must be a positive integer"
command -v sbatch >/dev/null || die "sbatch not found: is this a Slurm submit host? (local test cluster: bash $here/local_slurm.sh start)"

mkdir -p "$out/.deferred_farm/logs" "$state"
# The array indices whose frames are not all on disk yet.
tasks=$(python3 "$here/farm_summary.py" "$out" "$start" "$end" --missing-tasks "$per_task")
if [ -z "$tasks" ]; then
  echo "every frame of $start..$end is already in $out: nothing to submit" >&2
  exit 0
fi

gpus=${GPUS_PER_TASK:-1}
gres=()
if [ "$gpus" -gt 0 ]; then gres=(--gres="gpu:$gpus"); fi
submitted=$(date +%s.%N)
export DEFERRED_FARM_SCRIPTS="$here"
# shellcheck disable=SC2086
job=$(sbatch --parsable --array="$tasks" --job-name="deferred-$(basename "$blend" .blend)" \
  --output="$out/.deferred_farm/logs/slurm-%A_%a.out" "${gres[@]}" ${SLURM_RENDER_ARGS:-} \
  --export=ALL "$here/render_task.sh" "$blend" "$out" "$start" "$end" "$per_task")
job=${job%%;*}  # --parsable prints "id[;cluster]"
cat > "$state/$job.env" <<MANIFEST
BLEND=$(printf '%q' "$blend")
OUTDIR=$(printf '%q' "$out")
START=$start
END=$end
PER_TASK=$per_task
SUBMITTED=$submitted
MANIFEST
echo "$job"

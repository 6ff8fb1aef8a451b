#!/usr/bin/env bash
# Single-node Slurm "cluster" on this machine, for tests and workstation use.
#
# Usage:
#   bash scripts/cluster/local_slurm.sh start    # bring up munged + slurmctld + slurmd
#   bash scripts/cluster/local_slurm.sh status   # up/down, sinfo, squeue (exit 0 up, 3 down)
#   bash scripts/cluster/local_slurm.sh stop     # kill daemons, delete state (KEEP_STATE=1 keeps it)
#   eval "$(bash scripts/cluster/local_slurm.sh env)"   # just the export line
#
# Client commands (sbatch, squeue, scontrol, scancel, srun, sinfo) must see the
# generated config; `start` and `status` print the line to use:
#   export SLURM_CONF=<state>/slurm.conf
#
# Environment:
#   LOCAL_SLURM_DIR        state directory        (default /tmp/deferred-local-slurm)
#   LOCAL_SLURM_GPUS       number of fake GPUs     (default 4; 0 = no GRES)
#   LOCAL_SLURM_OVERSUB    jobs allowed per core   (default max(4, GPUS))
#   LOCAL_SLURM_CTLD_PORT  slurmctld port          (default 6817)
#   LOCAL_SLURM_SLURMD_PORT slurmd port            (default 6818)
#   LOCAL_SLURM_TIMEOUT    start-up timeout, s     (default 60)
#   KEEP_STATE=1           `stop` keeps the state directory (logs, jobcomp.log);
#                          `start` then reuses it (otherwise it wipes it first)
#
# Requires root (Debian packages slurmctld slurmd slurm-client munge; tested
# with Slurm 22.05.8 / munge 0.5.15, cgroup v1, no systemd).
#
# What it sets up -- everything lives in the state dir; /etc/slurm and
# /etc/munge are never read or written. `start` begins from an empty state
# dir (unless KEEP_STATE=1), so no jobs are resurrected from an old run.
#   munge/        private munged: generated 1 KiB key (0400), socket, pid,
#                 log, seed. The dir is 0711: without --force munged refuses
#                 a 0700 socket dir ("Socket is inaccessible").
#                 --force lets it replace a stale socket/lock of a killed run.
#   slurm.conf    AuthInfo=socket=<state>/munge/munge.socket.2 so Slurm (auth
#                 and job credentials) talks to our munged, not the system one.
#   gres.conf     AutoDetect=off + Name=gpu File=<state>/dev/gpu[0-N-1].
#                 The files are character device nodes (mknod c 195 <i>, the
#                 NVIDIA major, no driver behind them). With File= Slurm binds
#                 a GPU index to each job and exports CUDA_VISIBLE_DEVICES,
#                 SLURM_JOB_GPUS and GPU_DEVICE_ORDINAL as on a real GPU node.
#                 Plain files do NOT work: slurmd logs "is not a valid
#                 character or block device" and then exports nothing.
#   plugstack.conf  empty, so the system /etc/slurm/plugstack.conf.d SPANK
#                 plugins are not loaded.
#   jobcomp.log   JobCompType=jobcomp/filetxt: one line per finished job
#                 (JobState, ExitCode, NodeList, StartTime/EndTime,
#                 ArrayJobId/ArrayTaskId) -- how to query finished jobs without
#                 slurmdbd. `sacct` (AccountingStorageType=none) does not work,
#                 `sacct -c` reads this file but only prints a few columns.
#   ctld/, slurmd/, log/, run/  StateSaveLocation, SlurmdSpoolDir, logs, pids.
#
# Nonstandard settings and why:
#   NodeName uses the real hardware layout (`slurmd -C`) so slurmd does not
#     drain the node for a config mismatch; RealMemory = 90% of MemAvailable.
#     NodeAddr=127.0.0.1, SlurmctldHost=`hostname -s` if it resolves, else
#     localhost; slurmd is started with -N <that name>.
#   PartitionName ... OverSubscribe=FORCE:<N>: up to N jobs may share a core,
#     so a job array of 4 x --gres=gpu:1 runs all 4 tasks at once even on a
#     2-core machine; GPUs stay exclusive (GRES are never oversubscribed), as
#     on a real GPU node where the GPU, not the CPU, is the limit.
#   SelectType=select/cons_tres + CR_Core: needed for --gres=gpu tracking.
#     Memory is not a consumable resource.
#   ProctrackType=proctrack/linuxproc, TaskPlugin=task/none: no cgroups
#     needed (works in containers / without systemd), so no cgroup.conf and
#     no device constraint: CUDA_VISIBLE_DEVICES is the global GPU index.
#   JobAcctGatherType=jobacct_gather/none, AccountingStorageType=none: no
#     slurmdbd. Finished jobs: `scontrol show job` for MinJobAge=300 s, and
#     jobcomp.log until `stop`. (AccountingStorageTRES=gres/gpu would be
#     fatal without slurmdbd.)
#   SlurmUser=root, SlurmdUser=root: we run as root, no slurm user needed.
#   SchedulerParameters batch_sched_delay=0 (default 3 s): batch jobs start
#     ~0.3 s after sbatch. KillWait=5, bf_interval=5, SlurmdTimeout=30:
#     fast timers. ReturnToService=2: a restarted node comes back by itself.
#   MailProg=/bin/true: silences "Configured MailProg is invalid".
set -euo pipefail

STATE=${LOCAL_SLURM_DIR:-/tmp/deferred-local-slurm}
GPUS=${LOCAL_SLURM_GPUS:-4}
CTLD_PORT=${LOCAL_SLURM_CTLD_PORT:-6817}
SLURMD_PORT=${LOCAL_SLURM_SLURMD_PORT:-6818}
TIMEOUT=${LOCAL_SLURM_TIMEOUT:-60}
CLUSTER=deferred-local
PARTITION=local

CONF=$STATE/slurm.conf
MUNGE_DIR=$STATE/munge
MUNGE_SOCK=$MUNGE_DIR/munge.socket.2
MUNGE_PID=$MUNGE_DIR/munged.pid
CTLD_PID=$STATE/run/slurmctld.pid
SLURMD_PID=$STATE/run/slurmd.pid
MARKER=$STATE/.local_slurm_state
export SLURM_CONF=$CONF

log() { echo "local_slurm: $*" >&2; }
die() { log "ERROR: $*"; exit 1; }

[[ $STATE == /* && $STATE != / ]] || die "LOCAL_SLURM_DIR must be an absolute path, not /"
[[ $GPUS =~ ^[0-9]+$ ]] || die "LOCAL_SLURM_GPUS must be a number"

node_name() {
  local h
  h=$(hostname -s 2>/dev/null || true)
  if [[ -n $h ]] && getent hosts "$h" >/dev/null 2>&1; then echo "$h"; else echo localhost; fi
}

# alive PID: process exists and is not a zombie (a killed daemon whose
# parent does not reap it still has /proc/PID).
alive() {
  local st
  st=$(sed -n 's/^[0-9]* (.*) \([A-Za-z]\) .*/\1/p' "/proc/$1/stat" 2>/dev/null) || return 1
  [[ -n $st && $st != Z && $st != X ]]
}

# pid_of FILE COMM -> prints the pid if FILE names a live process called COMM
# (so a stale pid file whose pid was reused by another program is ignored).
pid_of() {
  local f=$1 comm=$2 pid
  [[ -r $f ]] || return 1
  pid=$(tr -dc '0-9' <"$f")
  [[ -n $pid ]] || return 1
  [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$comm" ]] || return 1
  alive "$pid" || return 1
  echo "$pid"
}

daemons_alive() {
  pid_of "$MUNGE_PID" munged >/dev/null && pid_of "$CTLD_PID" slurmctld >/dev/null &&
    pid_of "$SLURMD_PID" slurmd >/dev/null
}

is_up() { daemons_alive && timeout 10 scontrol ping 2>/dev/null | grep -q 'is UP'; }

export_line() { echo "export SLURM_CONF=$CONF"; }

port_busy() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

dump_logs() {
  local f
  for f in "$MUNGE_DIR/munged.log" "$STATE/log/slurmctld.log" "$STATE/log/slurmd.log" \
           "$STATE/log/launch.log"; do
    [[ -s $f ]] || continue
    echo "----- tail $f" >&2
    tail -n 25 "$f" >&2
  done
}

# wait_for SECONDS DESCRIPTION PIDFILE COMM CMD... : poll CMD every 0.2 s;
# give up at once if the daemon behind PIDFILE died (e.g. a fatal config
# error), or if it never wrote its pid file.
wait_for() {
  local secs=$1 what=$2 pidfile=$3 comm=$4; shift 4
  local start=$SECONDS
  until "$@" >/dev/null 2>&1; do
    if ((SECONDS - start >= secs)); then
      log "timed out after ${secs}s waiting for $what"
      dump_logs
      return 1
    fi
    if ! pid_of "$pidfile" "$comm" >/dev/null && { [[ -e $pidfile ]] || ((SECONDS - start >= 10)); }; then
      log "$comm exited (or never started) while waiting for $what"
      dump_logs
      return 1
    fi
    sleep 0.2
  done
}

node_idle() { [[ $(sinfo -h -n "$NODE" -o '%T' 2>/dev/null) == idle ]]; }

write_configs() {
  local hw mem_kb mem oversub gres_line=""
  # Real hardware layout, e.g. "CPUs=2 Boards=1 SocketsPerBoard=1 CoresPerSocket=2 ThreadsPerCore=1"
  hw=$(slurmd -C | head -n1 | grep -o 'CPUs=.*ThreadsPerCore=[0-9]*')
  mem_kb=$(awk '/^MemAvailable:/ {print $2}' /proc/meminfo)
  mem=$((mem_kb * 9 / 10 / 1024))
  oversub=${LOCAL_SLURM_OVERSUB:-$((GPUS > 4 ? GPUS : 4))}
  ((GPUS > 0)) && gres_line="Gres=gpu:$GPUS"

  cat >"$CONF" <<EOF
# Generated by scripts/cluster/local_slurm.sh -- do not edit (rewritten on start).
ClusterName=$CLUSTER
SlurmctldHost=$NODE
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root

AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MUNGE_SOCK
PlugStackConfig=$STATE/plugstack.conf

StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/slurmd
SlurmctldPidFile=$CTLD_PID
SlurmdPidFile=$SLURMD_PID
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info

SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$STATE/jobcomp.log
GresTypes=gpu
MailProg=/bin/true

ReturnToService=2
MinJobAge=300
SlurmdTimeout=30
SlurmctldTimeout=30
MessageTimeout=10
InactiveLimit=0
KillWait=5
WaitTime=0
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=5,batch_sched_delay=0,sched_min_interval=0

NodeName=$NODE NodeAddr=127.0.0.1 $hw RealMemory=$mem $gres_line State=UNKNOWN
PartitionName=$PARTITION Nodes=$NODE Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:$oversub
EOF

  {
    echo "# Generated by scripts/cluster/local_slurm.sh: fake GPUs (device nodes, no driver)."
    echo "AutoDetect=off"
    if ((GPUS > 0)); then
      echo "NodeName=$NODE Name=gpu File=$STATE/dev/gpu[0-$((GPUS - 1))]"
    fi
  } >"$STATE/gres.conf"
  # Fake GPUs: char device nodes like /dev/nvidia<i> (see header).
  local i dev
  for ((i = 0; i < GPUS; i++)); do
    dev=$STATE/dev/gpu$i
    [[ -c $dev ]] && continue
    rm -f "$dev"
    mknod -m 0666 "$dev" c 195 "$i" ||
      die "mknod $dev failed (needs root / CAP_MKNOD); Slurm requires device nodes for GPU binding"
  done
  : >"$STATE/plugstack.conf"
}

cmd_start() {
  local t0=$EPOCHREALTIME
  if daemons_alive; then
    if is_up; then
      log "already running (state in $STATE)"
      export_line
      return 0
    fi
    log "daemons alive but controller not answering; restarting"
  fi
  # Leftovers of a crashed/partial run: kill what is still alive, drop
  # stale pid files, and (unless KEEP_STATE=1) start from an empty state dir
  # so no jobs are resurrected from an old StateSaveLocation.
  if [[ -d $STATE ]]; then
    log "cleaning up after a previous run in $STATE"
    cmd_stop
  fi

  for p in "$CTLD_PORT" "$SLURMD_PORT"; do
    port_busy "$p" && die "port $p is already in use (another Slurm?); set LOCAL_SLURM_CTLD_PORT / LOCAL_SLURM_SLURMD_PORT"
  done

  NODE=$(node_name)
  # Permissions: munged insists the key is 0400 and that no directory on
  # the key/socket/log paths is group/other-writable. The munge dir is 0711
  # (not 0700) so non-root users can reach the socket; the rest is 0755 so
  # non-root users can read slurm.conf and submit jobs.
  umask 022
  mkdir -p "$STATE"
  chmod 0755 "$STATE"
  : >"$MARKER"
  mkdir -p "$MUNGE_DIR" "$STATE/ctld" "$STATE/slurmd" "$STATE/log" "$STATE/run" "$STATE/dev"
  chmod 0711 "$MUNGE_DIR"
  chmod 0700 "$STATE/ctld"
  if [[ ! -s $MUNGE_DIR/munge.key ]]; then
    (umask 077 && dd if=/dev/urandom of="$MUNGE_DIR/munge.key" bs=1 count=1024 status=none)
  fi
  chmod 0400 "$MUNGE_DIR/munge.key"
  write_configs
  : >"$STATE/log/launch.log"

  munged --force --key-file="$MUNGE_DIR/munge.key" --socket="$MUNGE_SOCK" \
    --pid-file="$MUNGE_PID" --log-file="$MUNGE_DIR/munged.log" \
    --seed-file="$MUNGE_DIR/munged.seed" >>"$STATE/log/launch.log" 2>&1 ||
    { dump_logs; die "munged failed to start"; }
  wait_for 10 "munged" "$MUNGE_PID" munged bash -c "munge -n -S '$MUNGE_SOCK' | unmunge -S '$MUNGE_SOCK'" || die "munged not working"

  slurmctld -f "$CONF" >>"$STATE/log/launch.log" 2>&1 || { dump_logs; die "slurmctld failed to start"; }
  wait_for "$TIMEOUT" "slurmctld" "$CTLD_PID" slurmctld bash -c "scontrol ping | grep -q 'is UP'" || die "slurmctld did not come up"

  slurmd -f "$CONF" -N "$NODE" >>"$STATE/log/launch.log" 2>&1 || { dump_logs; die "slurmd failed to start"; }
  wait_for "$TIMEOUT" "node $NODE idle" "$SLURMD_PID" slurmd node_idle || die "node did not become idle"

  # Smoke tests: srun, then a batch job. The batch one also absorbs
  # slurmctld's ~3 s warm-up before its first main-scheduler pass, so jobs
  # submitted right after `start` begin within ~0.3 s. (Not `sbatch --wait`:
  # it polls every 2 s with back-off and would add up to ~8 s.)
  timeout "$TIMEOUT" srun -N1 -n1 -t 1 true >>"$STATE/log/launch.log" 2>&1 ||
    { dump_logs; die "smoke test 'srun true' failed"; }
  local jid
  jid=$(sbatch --parsable -t 1 -J local_slurm_smoke -o /dev/null --wrap true 2>>"$STATE/log/launch.log") ||
    { dump_logs; die "smoke test: sbatch failed"; }
  wait_for "$TIMEOUT" "smoke batch job $jid" "$SLURMD_PID" slurmd bash -c \
    "scontrol -o show job '$jid' | grep -qE 'JobState=(COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|BOOT_FAIL|OUT_OF_MEMORY)'" ||
    die "smoke batch job did not finish"
  if ! scontrol -o show job "$jid" | grep -q 'JobState=COMPLETED'; then
    scontrol show job "$jid" >&2 || true
    dump_logs
    die "smoke batch job did not complete successfully"
  fi

  local t1=$EPOCHREALTIME
  log "up in $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}') s: node $NODE, $GPUS fake GPUs, state in $STATE"
  log "finished jobs are logged to $STATE/jobcomp.log"
  export_line
}

# Kill one daemon by pid file, TERM then KILL.
kill_daemon() {
  local f=$1 comm=$2 pid i
  if pid=$(pid_of "$f" "$comm"); then
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < 100; i++)); do
      alive "$pid" || break
      sleep 0.1
    done
    if alive "$pid"; then
      log "$comm ($pid) ignored SIGTERM; killing"
      kill -KILL "$pid" 2>/dev/null || true
      sleep 0.2
    fi
  fi
  rm -f "$f"
}

# Leftovers of jobs whose slurmd/slurmctld died: slurmstepd outlives slurmd,
# and job processes outlive their slurmstepd. Ours are recognised by
# slurmstepd holding a file under $STATE open (the slurmd log), and by job
# processes carrying SLURM_JOB_ID plus SLURM_CONF=$CONF in their environment
# (Slurm sets SLURM_CONF for every task). Never kills this script or its
# ancestors.
kill_job_leftovers() {
  local p pid fd self=" " q=$$ victims=()
  while [[ $q =~ ^[0-9]+$ ]] && ((q > 1)); do
    self+="$q "
    q=$(awk '{print $4}' "/proc/$q/stat" 2>/dev/null || true)
  done
  for p in /proc/[0-9]*; do
    pid=${p#/proc/}
    [[ $self == *" $pid "* ]] && continue
    case $(cat "$p/comm" 2>/dev/null) in
      slurmstepd)
        for fd in "$p"/fd/*; do
          if [[ $(readlink "$fd" 2>/dev/null) == "$STATE/"* ]]; then
            victims+=("$pid")
            break
          fi
        done ;;
      *)
        if grep -qzxF -- "SLURM_CONF=$CONF" "$p/environ" 2>/dev/null &&
           grep -qz '^SLURM_JOB_ID=' "$p/environ" 2>/dev/null; then
          victims+=("$pid")
        fi ;;
    esac
  done
  if ((${#victims[@]})); then
    log "killing ${#victims[@]} leftover job process(es): ${victims[*]}"
    kill -KILL "${victims[@]}" 2>/dev/null || true
  fi
}

stop_daemons() {
  if pid_of "$CTLD_PID" slurmctld >/dev/null && pid_of "$SLURMD_PID" slurmd >/dev/null; then
    # Cancel all jobs first so their steps are torn down the normal way.
    timeout 10 scancel -p "$PARTITION" 2>/dev/null || true
    local end=$((SECONDS + 15))
    while ((SECONDS < end)) && [[ -n $(timeout 5 squeue -h -t R,CG,S -p "$PARTITION" 2>/dev/null) ]]; do
      sleep 0.2
    done
  fi
  kill_daemon "$SLURMD_PID" slurmd
  kill_daemon "$CTLD_PID" slurmctld
  kill_daemon "$MUNGE_PID" munged
  kill_job_leftovers
}

cmd_stop() {
  if [[ ! -d $STATE ]]; then
    log "not running (no $STATE)"
    return 0
  fi
  stop_daemons
  if [[ ${KEEP_STATE:-0} == 1 ]]; then
    log "stopped; state kept in $STATE"
  elif [[ -e $MARKER ]]; then
    rm -rf -- "$STATE"
    log "stopped; removed $STATE"
  else
    log "stopped; $STATE has no $(basename "$MARKER") marker, not removing it"
  fi
}

cmd_status() {
  if is_up; then
    echo "local slurm: UP (state in $STATE)"
    export_line
    sinfo
    squeue
  else
    echo "local slurm: DOWN"
    return 3
  fi
}

case ${1:-} in
  start) cmd_start ;;
  stop) cmd_stop ;;
  status) cmd_status ;;
  env) export_line ;;
  *) echo "usage: $0 start|stop|status|env" >&2; exit 2 ;;
esac

#!/usr/bin/env bash
# A throwaway single-node Slurm cluster on localhost, for the job array test of `dala bench`
# (tests/tools/bench/slurm_bench_test.cc; docs/benchmarking.md "Slurm job array").
#
#   slurm_local.sh start DIR [OWNER_PID]   write DIR/slurm.conf and a munge key, start munged,
#                                          slurmctld and slurmd (as root) on free ports and wait
#                                          until the node is idle; prints SLURM_CONF=DIR/slurm.conf.
#                                          Exit 0: running; 3: Slurm cannot run here (the reason
#                                          on stderr, nothing left running); other: a failure.
#   slurm_local.sh stop DIR                cancel the jobs, stop every process of this cluster.
#
# Nothing outlives its owner: a failed start stops what it started (trap), and a watchdog stops
# the cluster when OWNER_PID (default: the caller) exits, or after DALA_SLURM_MAX_S seconds
# (default 280), whichever comes first. The processes of the cluster are found by the SLURM_CONF
# in their environment (slurmd, slurmstepd and the job scripts inherit it), never by name.
# Needs Debian's slurm-wlm (22.05) and munge: scripts/install_deps.sh --test.
set -uo pipefail
# Without SLURM_CONF in /proc/self/environ (a forked subshell keeps it): see cluster_pids.
if [ -n "${SLURM_CONF+x}" ]; then exec env -u SLURM_CONF "$0" "$@"; fi

cmd=${1:-}
dir=${2:-}
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR [OWNER_PID]" >&2; exit 2; }
dir=$(cd "$dir" 2>/dev/null && pwd) || { echo "$0: no folder $2" >&2; exit 2; }
conf=$dir/slurm.conf
log() { echo "[slurm_local] $*" >&2; }

# Processes whose environment holds SLURM_CONF=$conf: the daemons, slurmstepd, the job scripts
# and their children. Not this script, nor its callers, nor the commands of the pipeline below
# (SLURM_CONF is not in this script's environment, and set only on the Slurm commands it runs).
self_and_callers=$$
p=$$
while [ "$p" -gt 1 ] 2>/dev/null; do
  p=$(awk '{ print $4 }' "/proc/$p/stat" 2>/dev/null) || break
  self_and_callers="$self_and_callers $p"
done
cluster_pids() {
  local p
  for p in $(grep -lzxF "SLURM_CONF=$conf" /proc/[0-9]*/environ 2>/dev/null |
             sed -n 's|^/proc/\([0-9]*\)/environ$|\1|p'); do
    case " $self_and_callers $BASHPID " in *" $p "*) ;; *) echo "$p";; esac
  done
}

stop_cluster() {
  [ -f "$conf" ] || return 0
  # The watchdog, unless it is the one stopping the cluster (as our parent, or as us: bash may
  # exec the last command of a subshell in place).
  local w
  w=$(cat "$dir/watchdog.pid" 2>/dev/null)
  [ -n "$w" ] && [ "$w" != "$PPID" ] && [ "$w" != $$ ] && kill "$w" 2>/dev/null
  if [ -f "$dir/slurmctld.pid" ] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; then
    SLURM_CONF=$conf timeout 5 scancel --quiet --user=root 2>/dev/null
    for _ in $(seq 1 25); do  # The jobs end within KillWait (2 s).
      [ -z "$(SLURM_CONF=$conf timeout 5 squeue -h 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  local pids i
  for sig in TERM KILL; do
    pids=$(cluster_pids)
    [ -f "$dir/munge/munged.pid" ] && pids="$pids $(cat "$dir/munge/munged.pid")"
    # shellcheck disable=SC2086
    [ -n "${pids// /}" ] && kill -s "$sig" $pids 2>/dev/null
    for i in $(seq 1 30); do
      pids=$(cluster_pids)
      if [ -f "$dir/munge/munged.pid" ] && kill -0 "$(cat "$dir/munge/munged.pid")" 2>/dev/null; then
        pids="$pids munged"
      fi
      [ -z "${pids// /}" ] && break
      sleep 0.2
    done
    [ -z "${pids// /}" ] && break
    log "still running after SIG$sig: $(echo $pids)"
  done
  rm -f "$dir/munge/munged.pid"
  rm -rf "$dir/state" "$dir/spool"
}

if [ "$cmd" = stop ]; then
  stop_cluster
  exit 0
fi
[ "$cmd" = start ] || { echo "$0: unknown command $cmd" >&2; exit 2; }
owner=${3:-$PPID}
max_s=${DALA_SLURM_MAX_S:-280}

# 3 = Slurm cannot run here (the test skips); the reason is the last line on stderr.
cannot() { log "cannot run Slurm here: $*"; exit 3; }
for b in munged mungekey slurmctld slurmd sbatch sinfo squeue scancel; do
  command -v "$b" >/dev/null || cannot "$b is not installed (scripts/install_deps.sh --test)"
done
[ "$(id -u)" = 0 ] || cannot "starting slurmd needs root (uid $(id -u))"

trap 'stop_cluster' EXIT
mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
chmod 700 "$dir/munge"

# Free TCP ports: two consecutive ones nobody listens on.
port_used() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }  # Something answers there.
ctl_port=""
for _ in $(seq 1 50); do
  p=$(( 20000 + RANDOM % 30000 ))
  if ! port_used "$p" && ! port_used $((p + 1)); then ctl_port=$p; break; fi
done
[ -n "$ctl_port" ] || cannot "no free TCP port"
d_port=$((ctl_port + 1))

# The node as slurmd sees it; the documented bench.sbatch asks for 2 CPUs and 4G per task, so
# the node claims at least that (config_overrides: nothing is enforced without cgroups anyway).
hw=$(slurmd -C 2>/dev/null | head -1)
cpus=$(sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' <<< "$hw")
mem=$(sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' <<< "$hw")
[ -n "$cpus" ] || cannot "slurmd -C printed no CPUs: $hw"
[ "$cpus" -ge 2 ] || cpus=2
[ -n "$mem" ] && [ "$mem" -ge 4096 ] || mem=4096

cat > "$conf" <<EOF
ClusterName=dalatest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctl_port
SlurmdPort=$d_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
MinJobAge=300
KillWait=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
# SLURM_CONF is given to the daemons (so every process of the cluster has it, see cluster_pids)
# and to the commands run here, never exported in this script.

# munge: its own key, socket, pid, seed and log in DIR/munge (--force: root, /tmp parents).
mungekey --create --keyfile="$dir/munge/munge.key" --force >"$dir/log/mungekey.log" 2>&1 \
  || dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 2>/dev/null
chmod 600 "$dir/munge/munge.key"
SLURM_CONF=$conf munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munge/munged.pid" --seed-file="$dir/munge/munged.seed" \
  --log-file="$dir/log/munged.log" >>"$dir/log/munged.log" 2>&1 \
  || cannot "munged did not start: $(tail -3 "$dir/log/munged.log" | tr '\n' ' ')"

# The daemons in the foreground (-D), detached from the caller's terminal and process group.
SLURM_CONF=$conf setsid slurmctld -D -i -f "$conf" >>"$dir/log/slurmctld.out" 2>&1 < /dev/null &
ctld_pid=$!
SLURM_CONF=$conf setsid slurmd -D -N localhost -f "$conf" >>"$dir/log/slurmd.out" 2>&1 < /dev/null &
slurmd_pid=$!

# The watchdog: stops the cluster when the owner is gone or the time is up.
(
  trap - EXIT
  end=$((SECONDS + max_s))
  while kill -0 "$owner" 2>/dev/null && [ $SECONDS -lt $end ]; do sleep 1; done
  echo "watchdog: stopping"; "$0" stop "$dir"; echo "watchdog: stop exited $?"
) </dev/null >>"$dir/log/watchdog.log" 2>&1 &
echo $! > "$dir/watchdog.pid"
disown

# Wait for the node to be idle (30 s).
state=""
for _ in $(seq 1 150); do
  state=$(SLURM_CONF=$conf timeout 5 sinfo -h -n localhost -o %T 2>/dev/null | head -1)
  [ "$state" = idle ] && break
  kill -0 "$ctld_pid" 2>/dev/null && kill -0 "$slurmd_pid" 2>/dev/null || break  # One exited.
  sleep 0.2
done
if [ "$state" != idle ]; then
  for d in slurmd slurmctld; do
    log "--- $d log (last lines)"
    f=$dir/log/$d.log; [ -s "$f" ] || f=$dir/log/$d.out
    tail -n 5 "$f" 2>/dev/null | sed 's/^/    /' >&2
  done
  # The first error of slurmd, else of slurmctld (mpi/pmix fails harmlessly without PMIx).
  why=$(cat "$dir/log/slurmd.log" "$dir/log/slurmd.out" "$dir/log/slurmctld.log" \
          "$dir/log/slurmctld.out" 2>/dev/null | grep -iE "error|fatal" | grep -v pmix | head -1)
  if ! kill -0 "$slurmd_pid" 2>/dev/null; then
    cannot "slurmd exited: ${why:-no error logged}"
  elif ! kill -0 "$ctld_pid" 2>/dev/null; then
    cannot "slurmctld exited: ${why:-no error logged}"
  fi
  reason=$(SLURM_CONF=$conf timeout 5 sinfo -h -N -o "%T %E" 2>&1 | head -1)
  cannot "the node is not idle after 30 s (sinfo: '${reason:-no answer}'); ${why:-no error logged}"
fi
trap - EXIT
echo "SLURM_CONF=$conf"

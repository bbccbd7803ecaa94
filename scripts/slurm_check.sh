#!/usr/bin/env bash
# Runs the Slurm jobs written by `rbc-sweep SWEEP --slurm DIR` on a real, one-node Slurm cluster
# on this machine, and checks what a lab relies on:
#   1. the array job and the merge job of the demo sweep give the results.h5 of a local
#      `rbc-sweep` of the same sweep file;
#   then one submission of a sweep of two longer runs with a one-minute limit per task:
#   2. task 0, left alone, reaches its time limit: it stops at a checkpoint and requeues itself
#      (no one resubmits), and finishes;
#   3. task 1 is cancelled (scancel) mid-run; after `bash DIR/submit.sh` again it continues from
#      its checkpoint while task 0 returns at once;
#   4. the merged results.h5 then equals an uninterrupted local `rbc-sweep` of the same file.
# "Equal" is scripts/results_equal.py: every group, dataset and attribute bit-for-bit, except
# the provenance attributes created_by and evidence_wall_s.
#
# Needs root and Debian/Ubuntu: installs slurmctld, slurmd, slurm-client and munge with apt
# when missing, builds rbc-sweep, starts munged, slurmctld and slurmd as daemons with every file
# under a temporary folder (ports 16817/16818, nothing in /etc), and on exit, also on failure,
# cancels the jobs, stops the daemons and removes the folder. Prints PASS/FAIL per check and
# "N passed, M failed"; exits 1 when a check failed, 2 when the cluster could not be set up.
# Record each run of it (date, Slurm version, commit, outcome) in the table of README.md,
# "Scaling out".
#
# usage: bash scripts/slurm_check.sh
#   RBC_SLURM_PROFILE=dev    use the test build's rbc-sweep (default: a release build)
#   RBC_SLURM_KEEP=1         keep the temporary folder (logs, parts, results) for inspection
#   RBC_SLURM_LONG_T_S=8.0   simulated seconds of the fault checks' runs (must outlast ~30 s of wall)
set -uo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
START=$SECONDS
say() { echo "slurm_check: $*" >&2; }
die() { say "$*"; exit 2; }

[ "$(id -u)" = 0 ] || die "needs root (installs packages with apt, runs the Slurm daemons)"

# ---------------------------------------------------------------- install and build
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null \
  || ! command -v munged >/dev/null; then
  say "installing slurmctld slurmd slurm-client munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null && apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null \
    || die "apt-get install of slurmctld slurmd slurm-client munge failed"
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$REPO/target}"
PROFILE=${RBC_SLURM_PROFILE:-release}   # dev: the test build's binary (no release build)
cargo build --profile "$PROFILE" -q -p rbc --bin rbc-sweep || die "cargo build of rbc-sweep failed"
SWEEP="$CARGO_TARGET_DIR/$([ "$PROFILE" = dev ] && echo debug || echo "$PROFILE")/rbc-sweep"
EQUAL=(python3 "$REPO/scripts/results_equal.py")
python3 -c 'import h5py, numpy' 2>/dev/null || die "python3 with h5py and numpy is needed (scripts/setup.sh installs them)"
say "installed and built after $((SECONDS - START)) s"

# ---------------------------------------------------------------- a one-node cluster
W=$(mktemp -d /tmp/rbc-slurm.XXXXXX)
chmod 755 "$W"
mkdir -p "$W/munge" "$W/state" "$W/spool" "$W/log"
chmod 711 "$W/munge"
export SLURM_CONF="$W/slurm.conf"
started=()

teardown() {
  local rc=$?
  if [ -S "$W/munge/munge.socket" ] && [ -f "$W/slurmctld.pid" ]; then
    scancel --quiet --partition=rbc 2>/dev/null
    for _ in $(seq 30); do [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break; sleep 1; done
  fi
  if [ -n "${REFERENCE:-}" ] && kill -0 "$REFERENCE" 2>/dev/null; then
    kill $(pgrep -P "$REFERENCE") "$REFERENCE" 2>/dev/null
  fi
  for p in "${started[@]}"; do kill "$p" 2>/dev/null; done
  for p in "${started[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$p" 2>/dev/null && kill -9 "$p" 2>/dev/null
  done
  if [ "${RBC_SLURM_KEEP:-0}" = 1 ]; then say "kept $W"; else rm -rf "$W"; fi
  exit "$rc"
}
trap teardown EXIT
trap 'exit 130' INT TERM

mungekey --create --keyfile="$W/munge/munge.key" || die "mungekey failed"
munged --force --socket="$W/munge/munge.socket" --key-file="$W/munge/munge.key" \
  --pid-file="$W/munge/munged.pid" --seed-file="$W/munge/munged.seed" --log-file="$W/log/munged.log" \
  || die "munged did not start: $(tail -3 "$W/log/munged.log" 2>/dev/null)"
started+=("$(cat "$W/munge/munged.pid")")

cat >"$SLURM_CONF" <<EOF
ClusterName=rbccheck
SlurmctldHost=localhost
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# cred_expire is also how long a requeued job waits before it may start again (default 120 s)
AuthInfo=socket=$W/munge/munge.socket,cred_expire=5
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/log/slurmctld.log
SlurmdLogFile=$W/log/slurmd.log
# no cgroups in a container: track processes by parent pid, no task binding
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$W/log/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
# keep a timed-out job's grace short, and finished jobs visible to scontrol for 10 minutes
KillWait=5
OverTimeLimit=0
MinJobAge=600
# start a requeued job as soon as it may start again, not at the next default pass (30-60 s)
SchedulerParameters=sched_interval=5,bf_interval=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=rbc Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -f "$SLURM_CONF" || die "slurmctld did not start: $(tail -5 "$W/log/slurmctld.log" 2>/dev/null)"
for _ in $(seq 50); do [ -s "$W/slurmctld.pid" ] && break; sleep 0.1; done
started+=("$(cat "$W/slurmctld.pid")")
slurmd -f "$SLURM_CONF" -N localhost || die "slurmd did not start: $(tail -5 "$W/log/slurmd.log" 2>/dev/null)"
for _ in $(seq 50); do [ -s "$W/slurmd.pid" ] && break; sleep 0.1; done
started+=("$(cat "$W/slurmd.pid")")
for _ in $(seq 60); do [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break; sleep 1; done
[ "$(sinfo -h -o %T 2>/dev/null)" = idle ] || die "the node did not come up: $(sinfo 2>&1; tail -5 "$W/log/slurmctld.log" "$W/log/slurmd.log")"
say "cluster up after $((SECONDS - START)) s: $(sinfo -h -o '%P %D node, %c CPUs, %T')"

# ---------------------------------------------------------------- helpers
passed=0
failed=0
result() { # result NAME OK|message
  if [ "$2" = OK ]; then echo "PASS $1"; passed=$((passed + 1)); else echo "FAIL $1: $2"; failed=$((failed + 1)); fi
}

# submit DIR: run DIR/submit.sh; sets ARRAY and MERGE to the two job ids
submit() {
  local out
  out=$(bash "$1/submit.sh") || return 1
  ARRAY=$(sed -n 's/^array job \([0-9]*\)$/\1/p' <<<"$out")
  MERGE=$(sed -n 's/^Submitted batch job \([0-9]*\)$/\1/p' <<<"$out")
  [ -n "$ARRAY" ] && [ -n "$MERGE" ]
}

# wait_jobs SECONDS ID...: until none of the jobs is pending or running; 1 on timeout
wait_jobs() {
  local limit=$1 ids
  shift
  ids=$(IFS=,; echo "$*")
  for _ in $(seq "$limit"); do
    [ -z "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ] && return 0
    sleep 1
  done
  return 1
}

# states ID: "task state restarts" per array task (or "- state restarts" for a single job)
states() {
  scontrol -o show job "$1" | while read -r line; do
    local task state restarts
    task=$(grep -o ' ArrayTaskId=[^ ]*' <<<" $line" | cut -d= -f2)
    state=$(grep -o ' JobState=[^ ]*' <<<" $line" | cut -d= -f2)
    restarts=$(grep -o ' Restarts=[^ ]*' <<<" $line" | cut -d= -f2)
    echo "${task:--} $state $restarts"
  done | sort -n
}

# all_completed ID: every task (or the job) COMPLETED
all_completed() { [ -n "$(states "$1")" ] && ! states "$1" | awk '$2 != "COMPLETED" { bad = 1 } END { exit !bad }'; }

# equal A B: results_equal, its verdict on stderr
equal() { "${EQUAL[@]}" "$1" "$2" >&2; }

# ---------------------------------------------------------------- 1. array + merge = local sweep
check_demo() {
  local demo="$REPO/examples/sweeps/demo-poiseuille.toml" t0=$SECONDS
  "$SWEEP" "$demo" --out "$W/demo-local.h5" --jobs "$(nproc)" 2>"$W/log/demo-local.log" \
    || { result "array + merge = local" "local rbc-sweep failed: $(tail -1 "$W/log/demo-local.log")"; return; }
  say "local demo sweep: $((SECONDS - t0)) s"
  t0=$SECONDS
  "$SWEEP" "$demo" --slurm "$W/demo" 2>/dev/null || { result "array + merge = local" "rbc-sweep --slurm failed"; return; }
  submit "$W/demo" || { result "array + merge = local" "submit.sh failed"; return; }
  wait_jobs 600 "$ARRAY" "$MERGE" || { result "array + merge = local" "jobs still queued after 600 s"; return; }
  say "demo sweep on Slurm: $((SECONDS - t0)) s; $(states "$ARRAY" | tr '\n' ';') merge $(states "$MERGE")"
  all_completed "$ARRAY" || { result "array + merge = local" "array tasks not all COMPLETED: $(states "$ARRAY" | tr '\n' ';')"; return; }
  all_completed "$MERGE" || { result "array + merge = local" "merge job $(states "$MERGE")"; return; }
  [ "$(states "$ARRAY" | wc -l)" = 4 ] || { result "array + merge = local" "expected 4 array tasks"; return; }
  equal "$W/demo-local.h5" "$W/demo/results.h5" || { result "array + merge = local" "merged results.h5 differs from the local sweep"; return; }
  result "array + merge = local" OK
}

# The sweep of the fault checks: two runs of the demo capsule that never become steady (zero
# tolerances) and so last their whole simulated time (long enough for task 0 to outlive the
# signal ~30 s before its one-minute limit), checkpointed every 2 s of wall time.
LONG_T_S=${RBC_SLURM_LONG_T_S:-8.0}
write_long_sweep() { # write_long_sweep FILE
  cat >"$1" <<EOF
base_scene = "$REPO/examples/sweeps/demo-capsule.toml"
mean_velocity_mm_s = [1.0]
velocity_key = "flow.max_velocity_um_s"
r_init_um = [0.5, 1.0]
start_shapes = ["capsule"]
snapshot_every = 20
checkpoint_interval_s = 2.0
[start_shape.capsule]
shape = "sphere"
radius_um = 2.5
[steady]
window_s = 0.05
max_time_s = $LONG_T_S
position_tol_um = 1e-12
asphericity_tol = 1e-12
[classify]
frames = 10
[slurm]
time = "00:01:00"
stop_before_limit_s = 29
EOF
}

# t_s of run ID's last checkpoint (or last row) in FILE; empty when there is none yet
checkpoint_t() { "$SWEEP" --study-status "$1" --run "$2" --field t_s 2>/dev/null; }
positive() { awk -v t="$1" 'BEGIN { exit !(t > 0) }'; }

# ---------------------------------------------------------------- 2-4. faults: time limit, scancel
# One submission of the long sweep with a one-minute limit per task: task 0 is left alone and
# must outlive its limit by stopping at a checkpoint and requeueing itself; task 1 is cancelled
# right after a checkpoint past its start, then everything is submitted again. The final merge
# must equal the uninterrupted local sweep.
check_faults() {
  local t0=$SECONDS id0 id1 t st log0="$W/faults/logs/run-0.out" log1="$W/faults/logs/run-1.out"
  local limit="time limit: stop at a checkpoint, requeued by the script"
  local cancel="scancel a task mid-run, resubmit: it resumes from its checkpoint"
  local equalname="merged results after both faults = uninterrupted local sweep"
  id0=$(sed -n '2p' "$W/long-runs.tsv" | cut -f2)
  id1=$(sed -n '3p' "$W/long-runs.tsv" | cut -f2)
  fail_all() { result "$limit" "$1"; result "$cancel" "$1"; result "$equalname" "$1"; }
  "$SWEEP" "$W/long.toml" --slurm "$W/faults" 2>/dev/null || { fail_all "rbc-sweep --slurm failed"; return; }
  grep -q '^#SBATCH --signal=B:USR1@29$' "$W/faults/rbc-sweep.sbatch" || { fail_all "the array script lacks --signal=B:USR1@29"; return; }
  submit "$W/faults" || { fail_all "submit.sh failed"; return; }
  # cancel task 1 once it has a checkpoint after its start (checkpoints every 2 s), between two
  for _ in $(seq 300); do
    t=$(checkpoint_t "$W/faults/parts/1.h5" "$id1")
    [ -n "$t" ] && positive "$t" && break
    t=""
    sleep 1
  done
  [ -n "$t" ] || { fail_all "task 1 wrote no checkpoint after t = 0 within 300 s"; return; }
  sleep 1
  scancel "${ARRAY}_1"
  say "cancelled task 1 (${ARRAY}_1) after its checkpoint at t = $t s"
  wait_jobs 900 "$ARRAY" "$MERGE" || { fail_all "jobs still queued after 900 s"; return; }
  say "first submission: $((SECONDS - t0)) s; tasks (index state restarts): $(states "$ARRAY" | tr '\n' ';') merge $(states "$MERGE")"
  local first_t1 first_status
  first_t1=$(checkpoint_t "$W/faults/parts/1.h5" "$id1")
  first_status=$("$SWEEP" --study-status "$W/faults/results.h5" --run "$id1" --field status 2>/dev/null)

  # task 0: finished on its own, requeued at least once, never killed by the limit
  local restarts0 state0 msg=OK
  read -r _ state0 restarts0 < <(states "$ARRAY" | awk '$1 == 0')
  if [ "$state0" != COMPLETED ]; then msg="task 0 ended $state0 (restarts $restarts0)"
  elif [ "${restarts0:-0}" -lt 1 ]; then msg="task 0 was never requeued (its run ended within the first attempt: raise RBC_SLURM_LONG_T_S)"
  elif ! grep -q "stopped at a checkpoint before the time limit, requeued" "$log0"; then msg="task 0: no stop before the limit in its log"
  elif ! grep -q "$id0: resumed from its checkpoint at t = " "$log0"; then msg="task 0: no resume in its log"
  elif ! grep -q "attempt $((restarts0 + 1))," "$log0"; then msg="task 0: its log lacks attempt $((restarts0 + 1))"
  elif grep -q "DUE TO TIME LIMIT" "$log0"; then msg="task 0 was killed at its time limit"
  elif [ "$("$SWEEP" --study-status "$W/faults/results.h5" --run "$id0" --field status 2>/dev/null)" = running ]; then msg="task 0's run is unfinished in the merge"
  fi
  result "$limit" "$msg"

  # task 1: cancelled, unfinished with its checkpoint in the first merge; resubmitted, resumed
  st=$(states "$ARRAY" | awk '$1 == 1 { print $2 }')
  if [ "$st" != CANCELLED ]; then result "$cancel" "task 1 ended $st, not CANCELLED"; result "$equalname" "not reached"; return; fi
  if [ "$first_status" != running ] || ! positive "${first_t1:-0}"; then
    result "$cancel" "after the cancel the merge holds $id1 as '$first_status' with a checkpoint at t = '$first_t1'"; result "$equalname" "not reached"; return
  fi
  t0=$SECONDS
  submit "$W/faults" || { result "$cancel" "second submit.sh failed"; result "$equalname" "not reached"; return; }
  wait_jobs 900 "$ARRAY" "$MERGE" || { result "$cancel" "resubmitted jobs still queued after 900 s"; result "$equalname" "not reached"; return; }
  say "resubmission: $((SECONDS - t0)) s; tasks: $(states "$ARRAY" | tr '\n' ';') merge $(states "$MERGE")"
  local resumed
  resumed=$(grep -o "$id1: resumed from its checkpoint at t = [0-9.e+-]*" "$log1" | head -1)
  msg=OK
  if ! all_completed "$ARRAY" || ! all_completed "$MERGE"; then msg="resubmitted jobs: $(states "$ARRAY" | tr '\n' ';') merge $(states "$MERGE")"
  elif ! grep -q "task 0: run $id0 already " "$log0"; then msg="task 0 was run again instead of returning at once"
  elif [ "$(states "$ARRAY" | awk '$1 == 0 { print $3 }')" != 0 ]; then msg="task 0, finished, was requeued with task 1 ($(states "$ARRAY" | tr '\n' ';'))"
  elif [ -z "$resumed" ]; then msg="task 1 did not resume from its checkpoint (log: $(tail -2 "$log1" | tr '\n' ' '))"
  elif ! positive "${resumed##* }"; then msg="task 1 resumed from t = 0 ($resumed)"
  fi
  [ -n "$resumed" ] && say "$resumed (checkpoint read after the cancel: t = $first_t1 s)"
  result "$cancel" "$msg"

  if ! wait "$REFERENCE"; then result "$equalname" "local rbc-sweep of the long sweep failed: $(tail -1 "$W/log/long-local.log")"
  elif equal "$W/long-local.h5" "$W/faults/results.h5"; then result "$equalname" OK
  else result "$equalname" "merged results.h5 differs from the uninterrupted local sweep"; fi
}

check_demo
write_long_sweep "$W/long.toml"
"$SWEEP" "$W/long.toml" --list >"$W/long-runs.tsv" 2>"$W/log/list.log" || die "the long sweep is invalid: $(cat "$W/log/list.log")"
# the uninterrupted reference runs on this machine meanwhile (the cluster's cores idle between attempts)
( t0=$SECONDS
  "$SWEEP" "$W/long.toml" --out "$W/long-local.h5" --jobs "$(nproc)" 2>"$W/log/long-local.log" \
    && say "local long sweep (the reference of the fault checks): $((SECONDS - t0)) s" ) &
REFERENCE=$!
check_faults

echo "$passed passed, $failed failed ($((SECONDS - START)) s in all)"
[ "$failed" = 0 ]

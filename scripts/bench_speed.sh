#!/usr/bin/env bash
# Cost of a simulated ms of the paper's channel scene, this checkout against an older commit, side
# by side in one run, with the accuracy of each against a tight reference (issue 11).
#
#   bash scripts/bench_speed.sh [--old COMMIT] [--old-bin DIR] [--ms 5] [--cases rest,mid] [--no-reference] [--old-setting KEY=VALUE,...] [--new-setting KEY=VALUE,...] [--setting NAME:KEY=VALUE,...] [--reference KEY=VALUE,...] [--no-pair] [--jobs N]
#
# The issue's own comparison, the study's setting today against commit 33cbdd2's (the scene it
# ran: ROS34PW2-local at 1e-3 um, no step cap):
#
#   bash scripts/bench_speed.sh --old-setting 'scheme="ros34pw2-local",atol_um=1e-3,h_max_s='
#
# and over the first 20 ms from rest, which holds the rim's strained stretch (6-10 ms) that the
# 5 ms window ends before (solver/README.md, "Session 29"):
#
#   bash scripts/bench_speed.sh --cases rest --ms 20 --old-setting 'scheme="ros34pw2-local",atol_um=1e-3,h_max_s='
#
# (`--ms 20` with both cases: session 30's pairs on an Intel Xeon, solver/README.md "Session 30";
# core-s per simulated ms depend on the CPU, 1.7-2x between the AMD EPYC of sessions 27-29 and
# that Xeon, the ratio to old much less: 0.18-0.20 over 20 ms from rest on both. There the bs23
# references of 20 ms take hours: `--no-reference` reuses a case's last one, if it was run with the same `--reference`
# setting: otherwise it runs again.)
#
# --old-bin DIR: a folder holding the old commit's rbc-simulate already built (e.g. the study's
# binary), instead of building COMMIT here.
#
# Cases: `rest`, the study's scene (examples/studies/science-6p5/scene.toml) with the cell
# started at r_init = 1.2 um; `mid`, the same scene started from the r_init = 1.2 um run's
# shape at 20 ms (the last snapshot of examples/fixtures/science-6p5-r1.2.h5; see its README);
# `state:STUDY/RUN[@COMMIT]`, run RUN of a study resumed from its committed state
# (examples/studies/STUDY/state/RUN.h5 and its checkpoint, as committed in COMMIT when given,
# else as in this checkout: the state moves on with every save), with the run's own scene as
# its checkpoint holds it (penalty walls included; the step method it runs with now, which the
# results' first scene may not be: the ~4 mm/s column started with ROS34PW2 and steps with
# RosW6S4) and compared from the checkpoint on (`rbc-bench compare --from-s`);
# a run that ended goes on from the checkpoint of its end (reopened in the bench's copy);
# e.g. the settled croissant and the slipper of solver/README.md "Session 33":
#
#   bash scripts/bench_speed.sh --old 15c6757 --ms 10 --reference 'scheme="bs23",atol_um=4e-5,wall_atol_um=4e-5' \
#     --cases state:science-6p5-penalty/discocyte_u3.8_r0.8@0575477,state:science-6p5-penalty/discocyte_u3.8_r1@0575477
# Each case runs for --ms simulated ms with
#   old: the old commit's rbc-simulate, the scene as it is (with --old-setting: its [integrator]
#        keys replaced, `KEY=` with no value removes the key);
#   new: this checkout's rbc-simulate, the same scene (with --new-setting: its [integrator] keys
#        replaced, so that a proposed setting runs side by side with the old code's);
#   reference: this checkout, the paper's integrator (bs23) at atol 4e-5 um (--no-reference skips it;
#        --reference KEY=VALUE,... sets its [integrator] keys instead, e.g. a tighter atol);
#   and every --setting: this checkout with the scene's [integrator] keys replaced, --jobs at a
#        time (default 1).
# --no-pair skips old and new: a work-precision table of this checkout's settings alone, e.g.
#
#   bash scripts/bench_speed.sh --no-pair --jobs 2 --reference 'scheme="bs23",atol_um=1e-5' \
#     --setting 'bs23@4e-5:scheme="bs23",atol_um=4e-5' --setting 'ros34pw2-mobility@2e-3:atol_um=2e-3' ...
#
# (scripts/work_precision.sh runs the whole table of solver/README.md this way).
# old and new run at the same time, one thread each (RAYON_NUM_THREADS=1), so background load
# biases both alike; the reference runs after them. CPU time is the process's user + system time.
# Prints one table per case (rbc-bench compare): core-s per simulated ms, the cost ratio to old,
# the largest deviation of centroid y, z, asphericity and x-velocity from the reference, and the
# drift of y from it (um/s, the least-squares slope of y - y_ref: a lateral bias that grows with time).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OLD=33cbdd2
OLD_BIN=
MS=5
CASES=rest,mid
REFERENCE=1
REFERENCE_SETTING='scheme="bs23",atol_um=4e-5'
PAIR=1
JOBS=1
SETTINGS=()
NEW_SETTING=
OLD_SETTING=
while [ $# -gt 0 ]; do
  case $1 in
    --old) OLD=$2; shift 2 ;;
    --old-bin) OLD_BIN=$2; shift 2 ;;
    --ms) MS=$2; shift 2 ;;
    --cases) CASES=$2; shift 2 ;;
    --no-reference) REFERENCE=0; shift ;;
    --setting) SETTINGS+=("$2"); shift 2 ;;
    --new-setting) NEW_SETTING=$2; shift 2 ;;
    --old-setting) OLD_SETTING=$2; shift 2 ;;
    --reference) REFERENCE_SETTING=$2; shift 2 ;;
    --no-pair) PAIR=0; shift ;;
    --jobs) JOBS=$2; shift 2 ;;
    *) echo "usage: bash scripts/bench_speed.sh [--old COMMIT] [--old-bin DIR] [--ms 5] [--cases rest,mid] [--no-reference] [--old-setting KEY=VALUE,...] [--new-setting KEY=VALUE,...] [--setting NAME:KEY=VALUE,...] [--reference KEY=VALUE,...] [--no-pair] [--jobs N]" >&2; exit 2 ;;
  esac
done
WORK=${RBC_BENCH_WORK:-/tmp/rbc-bench-speed}
mkdir -p "$WORK"
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/work/target}
mkdir -p "$CARGO_TARGET_DIR" 2>/dev/null || export CARGO_TARGET_DIR=$ROOT/target
if ! pkg-config --exists hdf5 2>/dev/null; then bash scripts/setup.sh; fi

if [ "$PAIR" = 1 ]; then echo "bench_speed: building this checkout ($(git rev-parse --short HEAD)) and $OLD" >&2; else echo "bench_speed: building this checkout ($(git rev-parse --short HEAD))" >&2; fi
cargo build --release --quiet --bin rbc-simulate --bin rbc-bench --bin rbc-sweep
NEW_BIN=$CARGO_TARGET_DIR/release
if [ "$PAIR" = 0 ]; then
  :
elif [ -z "$OLD_BIN" ]; then
  OLD_SRC=$WORK/old-$OLD
  if [ ! -d "$OLD_SRC" ]; then git worktree add --detach "$OLD_SRC" "$OLD" >/dev/null; fi
  (cd "$OLD_SRC" && CARGO_TARGET_DIR=$WORK/target-old cargo build --release --quiet --bin rbc-simulate)
  OLD_BIN=$WORK/target-old/release
fi
[ "$PAIR" = 0 ] || [ -x "$OLD_BIN/rbc-simulate" ] || { echo "bench_speed: $OLD_BIN/rbc-simulate: no such program" >&2; exit 2; }

STUDY=$ROOT/examples/studies/science-6p5
FIXTURE=$ROOT/examples/fixtures/science-6p5-r1.2.h5
END_S=$(awk -v m="$MS" 'BEGIN { printf "%.6g", m * 1e-3 }')

# scene of a case: the study's scene, cell placed (and for `mid` taken from the fixture), end time --ms;
# for `state:STUDY/RUN` the run's own scene as its checkpoint holds it (the step method it runs with now),
# end time --ms after its checkpoint
scene_for() {
  local case=$1 out=$2
  if [[ $case == state:* ]]; then
    local run file
    run=$(state_run "$case")
    file=$(state_file "$case")
    [ -f "$file" ] && [ -f "$file.$run.ckpt" ] || { echo "bench_speed: $case: no $file with its checkpoint" >&2; exit 2; }
    local t_s end
    t_s=$("$NEW_BIN/rbc-sweep" status "$file" --run "$run" --field t_s)
    end=$(awk -v t="$t_s" -v m="$MS" 'BEGIN { printf "%.10f", t + m * 1e-3 }')
    # the checkpoint's scene is the one the run steps with now (the results' `scene` attribute
    # keeps the first one of a run that switched its scheme; a checkpoint without one falls back to it)
    HDF5_USE_FILE_LOCKING=FALSE python3 -c 'import sys, h5py
c = h5py.File(sys.argv[1] + "." + sys.argv[2] + ".ckpt", "r").attrs
a = c["scene"] if "scene" in c else h5py.File(sys.argv[1], "r")["runs/" + sys.argv[2]].attrs["scene"]
sys.stdout.write(a if isinstance(a, str) else a.decode())' "$file" "$run" \
      | sed -e "s/^end_s = .*/end_s = $end/" > "$out"
    return
  fi
  case $case in
    rest) sed -e 's/^position_um = .*/position_um = [0.0, 1.0490, 0.5828]/' ;;
    mid)
      local yz
      yz=$("$NEW_BIN/rbc-sweep" --study-status "$FIXTURE" --run discocyte_u3.8_r1.2 --field y_um,z_um)
      read -r y z <<< "$yz"
      sed -e "s|^shape = \"discocyte\".*|shape = \"mesh-from-results\"\nresults = \"$FIXTURE\"\nrun = \"discocyte_u3.8_r1.2\"\nsnapshot = -1|" \
          -e "s/^position_um = .*/position_um = [0.0, $y, $z]/" -e '/^axis = /d' ;;
    *) echo "bench_speed: unknown case $case (rest, mid, state:STUDY/RUN)" >&2; exit 2 ;;
  esac < "$STUDY/scene.toml" | sed -e "s/^end_s = .*/end_s = $END_S/" -e "s/^name = .*/name = \"$case\"/" > "$out"
}

# the scene with [integrator] keys replaced: KEY=VALUE,KEY=VALUE
with_integrator() {
  local scene=$1 kv=$2 out=$3
  cp "$scene" "$out"
  IFS=',' read -ra pairs <<< "$kv"
  for p in "${pairs[@]}"; do
    local k=${p%%=*} v=${p#*=}
    if [ -z "$v" ]; then
      sed -i "/^\[integrator\]/,/^\[/ {/^$k = /d}" "$out"
    elif grep -q "^$k = " "$out"; then
      sed -i "/^\[integrator\]/,/^\[/ s|^$k = .*|$k = $v|" "$out"
    else
      sed -i "s|^\[integrator\]|[integrator]\n$k = $v|" "$out"
    fi
  done
}

# the run of a case `state:STUDY/RUN[@COMMIT]`
state_run() {
  local spec=${1#state:}
  spec=${spec%@*}
  echo "${spec##*/}"
}

# its study's sweep file (this checkout's)
state_sweep() {
  local spec=${1#state:}
  echo "$ROOT/examples/studies/${spec%%/*}/sweep.toml"
}

# its results file: examples/studies/STUDY/state/RUN.h5, or with @COMMIT that file and its
# checkpoint as they were committed there (git show, into $WORK/state-COMMIT/)
state_file() {
  local spec=${1#state:} commit=
  if [[ $spec == *@* ]]; then commit=${spec##*@}; spec=${spec%@*}; fi
  local study=${spec%%/*} run=${spec##*/}
  if [ -z "$commit" ]; then
    echo "$ROOT/examples/studies/$study/state/$run.h5"
    return
  fi
  local dir=$WORK/state-$commit
  mkdir -p "$dir"
  for f in "$run.h5" "$run.h5.$run.ckpt"; do
    [ -s "$dir/$f" ] || git -C "$ROOT" show "$commit:examples/studies/$study/state/$f" > "$dir/$f" || { echo "bench_speed: $1: no $f in $commit" >&2; rm -f "$dir/$f"; exit 2; }
  done
  echo "$dir/$run.h5"
}

# run BIN SCENE OUT: prints the process CPU seconds, or FAILED (the diagnosis is in OUT.log);
# for a `state:` case ($c) OUT starts as a copy of the run's state and its checkpoint (--resume)
run() {
  rm -f "$3" "$3".*.ckpt
  local resume=()
  if [[ $c == state:* ]]; then
    local file run
    run=$(state_run "$c")
    file=$(state_file "$c")
    cp "$file" "$3"
    cp "$file.$run.ckpt" "$3.$run.ckpt"
    # a run that ended (a settled croissant, a slipper's orbit) goes on from the checkpoint of
    # its end state: the copy is reopened (`rbc-sweep reopen`, with the study's sweep file for
    # its snapshot cadence)
    case $("$NEW_BIN/rbc-sweep" status "$3" --run "$run" --field status) in
      steady|periodic|unsteady) "$NEW_BIN/rbc-sweep" reopen "$3" "$run" --sweep "$(state_sweep "$c")" > /dev/null ;;
    esac
    resume=(--resume)
  fi
  if /usr/bin/time -f "%U %S" -o "$3.time" env RAYON_NUM_THREADS=1 "$1/rbc-simulate" "$2" --out "$3" "${resume[@]}" > "$3.log" 2>&1; then
    awk '{ printf "%.1f", $1 + $2 }' "$3.time"
  else
    echo "bench_speed: $1/rbc-simulate $2 failed: $(grep -v '^\s*$' "$3.log" | tail -1)" >&2
    echo FAILED
  fi
}

IFS=',' read -ra case_list <<< "$CASES"
for c in "${case_list[@]}"; do
  d=$WORK/${c//[:\/]/_}
  mkdir -p "$d"
  scene_for "$c" "$d/scene.toml"
  entries=()
  failed=()
  add() { # NAME FILE CPU
    if [ "$3" = FAILED ]; then failed+=("$1: $(grep -v '^\s*$' "$2.log" | tail -1)"); else entries+=("$1=$2@$3"); fi
  }
  if [ "$PAIR" = 1 ]; then
    echo "bench_speed: case $c, $MS ms: old and new side by side" >&2
    if [ -n "$OLD_SETTING" ]; then with_integrator "$d/scene.toml" "$OLD_SETTING" "$d/old.toml"; else cp "$d/scene.toml" "$d/old.toml"; fi
    run "$OLD_BIN" "$d/old.toml" "$d/old.h5" > "$d/old.cpu" &
    pid_old=$!
    if [ -n "$NEW_SETTING" ]; then with_integrator "$d/scene.toml" "$NEW_SETTING" "$d/new.toml"; else cp "$d/scene.toml" "$d/new.toml"; fi
    run "$NEW_BIN" "$d/new.toml" "$d/new.h5" > "$d/new.cpu" &
    pid_new=$!
    wait $pid_old
    wait $pid_new
    add old "$d/old.h5" "$(cat "$d/old.cpu")"
    add new "$d/new.h5" "$(cat "$d/new.cpu")"
  fi
  # the reference (first: the longest) and the settings, --jobs at a time, each timed as its own
  # process (user + system CPU seconds)
  pool() { while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n || true; done; }
  # (--no-reference reuses the last reference of this case only when it was made with the same setting)
  if [ "$REFERENCE" = 1 ] || [ ! -f "$d/reference.h5" ] || [ ! -f "$d/reference.cpu" ] || [ "$(cat "$d/reference.setting" 2>/dev/null)" != "$REFERENCE_SETTING" ]; then
    echo "$REFERENCE_SETTING" > "$d/reference.setting"
    with_integrator "$d/scene.toml" "$REFERENCE_SETTING" "$d/reference.toml"
    echo "bench_speed: case $c: reference ($REFERENCE_SETTING)" >&2
    run "$NEW_BIN" "$d/reference.toml" "$d/reference.h5" > "$d/reference.cpu" &
    pool
  fi
  names=()
  for s in "${SETTINGS[@]}"; do
    name=${s%%:*}
    names+=("$name")
    with_integrator "$d/scene.toml" "${s#*:}" "$d/$name.toml"
    echo "bench_speed: case $c: setting $name" >&2
    run "$NEW_BIN" "$d/$name.toml" "$d/$name.h5" > "$d/$name.cpu" &
    pool
  done
  wait
  for name in "${names[@]}"; do add "$name" "$d/$name.h5" "$(cat "$d/$name.cpu")"; done
  echo
  if [ "$PAIR" = 1 ]; then
    echo "case $c ($MS ms; old = $OLD${OLD_SETTING:+ with $OLD_SETTING}, new = $(git rev-parse --short HEAD)${NEW_SETTING:+ with $NEW_SETTING}; reference $REFERENCE_SETTING)"
  else
    echo "case $c ($MS ms; $(git rev-parse --short HEAD); reference $REFERENCE_SETTING)"
  fi
  # (a `state:` case: the runs share the state's history up to its checkpoint, compared from there on)
  from=()
  if [[ $c == state:* ]]; then from=(--from-s "$("$NEW_BIN/rbc-sweep" status "$(state_file "$c")" --run "$(state_run "$c")" --field t_s)"); fi
  "$NEW_BIN/rbc-bench" compare "$d/reference.h5@$(cat "$d/reference.cpu")" "${entries[@]}" "${from[@]}"
  for f in "${failed[@]}"; do echo "failed: $f"; done
done

#!/usr/bin/env bash
# A study that lives in the repository and advances every session (examples/studies/NAME/).
#
#   bash scripts/study.sh resume NAME [--jobs N] [--first RUN,...]
#                                                  # continue every unfinished run in the background (nice 19);
#                                                  # the runs named by --first (default: the study's file
#                                                  # `first`, a run id a line) take the jobs first, in that order
#   bash scripts/study.sh save NAME                # suspend the runs at a checkpoint, copy their state into the folder
#   bash scripts/study.sh status NAME              # the progress table (running copies when there are, else the saved state;
#                                                  # while the study runs, a run that waits for a job (--jobs) is `waiting`,
#                                                  # also one not started yet, which is `not started` otherwise);
#                                                  # on stderr the runs of the saved state whose cell turned over
#                                                  # or folded, with the intervals (`rbc-sweep events`)
#   bash scripts/study.sh reopen NAME RUN          # let a run that ended (steady, periodic, unsteady) continue from its end
#   bash scripts/study.sh relabel NAME             # labels of the ended runs again from their evidence (`rbc-sweep relabel`)
#
# The folder holds sweep.toml (and its scene), state/RUN.h5 (each run's results so far: time
# series, a shape every snapshot_every outputs) with state/RUN.h5.RUN.ckpt (its latest
# checkpoint), and ledger.csv (which commit computed which stretch of simulated time, its
# cost and on which CPU). `resume` copies the state into a work folder (RBC_STUDY_WORK, default /tmp/rbc-study/NAME)
# and runs each unfinished run as a sweep task there (`rbc-sweep sweep.toml --task I`) at nice 19:
# it takes idle cores only, so benchmarks and builds beside it keep the machine. At most --jobs
# runs go at once; when one ends on its own, the next waiting run starts with the same binary. `save` asks the
# runs to stop at their next checkpoint (the file RUN.h5.suspend), waits for them and copies the
# results file and its checkpoint back into state/, appends the ledger and redraws
# trajectories.svg (y, z and asphericity against time of every run; with a file compare-with
# naming a sibling study of the same grid, also vs-SIBLING.svg: the runs both hold); commit the folder
# afterwards. A run resumes only from a checkpoint of the same scene text: keep the scene's
# values (a faster solver may resume an old checkpoint). `reopen` sets a run of state/ that
# ended back to running at its last state (`rbc-sweep reopen`), e.g. after the sweep's [steady]
# criterion was made stricter; the next `resume` continues it (commit state/ in between; a run
# with penalty walls that ended before session 28, when runs began to keep the checkpoint of
# their end, is refused: the results do not hold its walls' displacements).
# `relabel` decides the labels of the saved runs at rest again from their stored evidence under
# today's classification rule (this checkout's, built for it), and carries the steady state of a run that ended before 10 mm
# there (`rbc-sweep relabel`); runs that are running are left alone. For the repository's own
# study science-6p5, `save`, `reopen` and `relabel` then merge its ended runs into
# examples/results.h5 again (`bash scripts/examples.sh results`), which the README's rbc-predict
# example reads and tests/science_6p5.rs holds to the state; for either study they draw
# docs/radial_offset.png and .svg again (`rbc-sweep offsets` of both studies' state, the README's
# figure), docs/phase_studies.png and .svg (`rbc-sweep phase`, the README's phase diagrams),
# docs/croissant-start/phase_studies.png and .svg (the same of the croissant starts, `--start
# croissant`: the paper's Fig. 5 b) and docs/steady_studies.png and .svg (`rbc-sweep steady`, the
# README's Fig. 6), with this checkout's rbc-sweep; tests/science_6p5.rs holds the four SVGs to
# the state.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

usage() { echo "usage: bash scripts/study.sh resume|save|status|relabel NAME [--jobs N] [--first RUN,...] | reopen NAME RUN" >&2; exit 2; }
[ $# -ge 2 ] || usage
CMD=$1
NAME=$2
shift 2
RUN_ARG=
if [ "$CMD" = reopen ]; then
  [ $# -eq 1 ] || usage
  RUN_ARG=$1
  shift
fi
JOBS=2
FIRST=
FIRST_FLAG=
while [ $# -gt 0 ]; do
  case $1 in
    --jobs) JOBS=${2:?--jobs needs a number}; shift 2 ;;
    --first) FIRST=${2:?--first needs run ids}; FIRST_FLAG=$FIRST; shift 2 ;;
    *) usage ;;
  esac
done
# RBC_STUDY_ROOT (a folder of studies, default examples/studies) and RBC_SWEEP_BIN (an rbc-sweep
# binary to use instead of building this checkout's) are for tests.
STUDY=${RBC_STUDY_ROOT:-$ROOT/examples/studies}/$NAME
[ -f "$STUDY/sweep.toml" ] || { echo "study.sh: $STUDY/sweep.toml: no such study" >&2; exit 2; }
# The runs that take the jobs first when `resume` names none: the study's file `first`, one run
# id a line (text from a `#` on is a comment), committed with the study, so that every session
# resumes in the order the last one left. `--first` overrides it. A refill (a run ended and
# freed its job) reads the file again, so that a run queued in it while the study runs takes the
# next free job; an order given by `--first` holds for the refills of that resume.
if [ -z "$FIRST" ] && [ -f "$STUDY/first" ]; then
  FIRST=$(sed 's/#.*//' "$STUDY/first" | awk 'NF { print $1 }' | paste -sd, -)
fi
WORK=${RBC_STUDY_WORK:-/tmp/rbc-study}/$NAME
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/work/target}
mkdir -p "$CARGO_TARGET_DIR" 2>/dev/null || export CARGO_TARGET_DIR=$ROOT/target

# The state's labels are decided again under this checkout's classifier (`rbc-sweep relabel`), and
# examples/results.h5 is the ended runs of the repository's study science-6p5: merged again
# whenever its saved state changed (not for the studies of tests, under RBC_STUDY_ROOT).
# docs/radial_offset.png (the README's Fig. 4 column at ~6.5 mm/s, both walls),
# docs/phase_studies.png (the README's phase diagrams, both walls; of the croissant starts in
# docs/croissant-start/) and docs/steady_studies.png
# (the README's Fig. 6: steady radial position and slipper extents against the velocity, both
# walls) are drawn again from the two studies' state by this checkout's rbc-sweep whenever
# either's changed.
publish() {
  [ -z "${RBC_STUDY_ROOT:-}" ] || return 0
  [ "$NAME" = science-6p5 ] || [ "$NAME" = science-6p5-penalty ] || return 0
  # the merge and the figures are this checkout's (the tests hold them to what its rbc-sweep
  # makes), not those of the binary the runs go on with, which may be older; a failed build
  # leaves them as they were (the state is saved already)
  if [ -z "${BIN:-}" ] && ! compile; then
    echo "study.sh: this checkout's rbc-sweep did not build: examples/results.h5 and docs/ not made again (the state is saved)" >&2
    return 0
  fi
  # the labels of the runs that ended are this checkout's rule's too: a run that ended under an
  # older binary's classifier thresholds is decided again from its stored evidence
  "$BIN" relabel "$STUDY"/state/*.h5 --sweep "$STUDY/sweep.toml" 2>&1 | grep -- ' -> ' >&2 || true
  if [ "$NAME" = science-6p5 ]; then
    RBC_SWEEP_BIN="$BIN" bash "$ROOT/scripts/examples.sh" results && echo "study.sh: examples/results.h5 merged again from the ended runs; commit it with the study" >&2
  fi
  local studies=("$ROOT"/examples/studies/science-6p5/state/*.h5 "$ROOT"/examples/studies/science-6p5-penalty/state/*.h5)
  draw_doc radial_offset offsets "${studies[@]}" --mark-um 0.7
  draw_doc phase_studies phase "${studies[@]}"
  draw_doc croissant-start/phase_studies phase "${studies[@]}" --start croissant
  draw_doc steady_studies steady "${studies[@]}"
}

# draw_doc [FOLDER/]NAME COMMAND ARGS...: docs/[FOLDER/]NAME.png and .svg by `rbc-sweep COMMAND
# ARGS... --out docs[/FOLDER]` (NAME is the file the command writes), or the command's own error
# and the line to draw it by hand.
draw_doc() {
  local name=$1 command=$2 err flags out
  shift 2
  out=docs
  [ "$(dirname "$name")" = . ] || out=docs/$(dirname "$name")
  # the options after the files, for the line by hand
  flags=$(printf ' %s' "$@" | grep -o ' --.*' || true)
  if err=$("$BIN" "$command" "$@" --out "$ROOT/$out" 2>&1 >/dev/null); then
    echo "study.sh: docs/$name.png and .svg drawn again; commit them with the study" >&2
  else
    echo "study.sh: docs/$name.png could not be drawn: $(tail -n 1 <<< "$err"); draw it with this checkout's rbc-sweep: rbc-sweep $command examples/studies/science-6p5/state/*.h5 examples/studies/science-6p5-penalty/state/*.h5$flags --out $out" >&2
  fi
}

# The binary of this checkout (RBC_SWEEP_BIN when set) in BIN.
compile() {
  local bin=${RBC_SWEEP_BIN:-}
  if [ -z "$bin" ]; then
    if ! pkg-config --exists hdf5 2>/dev/null; then bash scripts/setup.sh || return 1; fi
    cargo build --release --quiet --bin rbc-sweep || return 1
    bin=$CARGO_TARGET_DIR/release/rbc-sweep
  else
    # the ledger records HEAD as the runs' commit: a binary built earlier would be misattributed
    local changed
    changed=$(git log -1 --format=%ct -- solver src data-schema 2>/dev/null)
    # (a shallow clone may not hold that commit: HEAD's time then bounds it)
    [ -n "$changed" ] || changed=$(git log -1 --format=%ct 2>/dev/null || echo 0)
    if [ "$(stat -c %Y "$bin" 2>/dev/null || echo 0)" -lt "${changed:-0}" ]; then
      echo "study.sh: warning: RBC_SWEEP_BIN ($bin) is older than the last commit that changed the solver ($(git log -1 --format=%h -- solver src data-schema)); the ledger will record $(git rev-parse --short HEAD) as its commit: rebuild it, or unset RBC_SWEEP_BIN to let study.sh build" >&2
    fi
  fi
  BIN=$bin
}

# The binary of this checkout, copied into the work folder so that rebuilding the checkout
# while the study runs does not change the program under it (a copy of its own per process:
# a `status` beside a `resume` may build at the same time).
build() {
  compile
  mkdir -p "$WORK/bin"
  cp "$BIN" "$WORK/bin/rbc-sweep.new.$$"
  mv "$WORK/bin/rbc-sweep.new.$$" "$WORK/bin/rbc-sweep"
  git rev-parse --short HEAD > "$WORK/bin/commit"
  if ! git diff --quiet HEAD -- solver src data-schema ':!*.md' 2>/dev/null; then echo "+dirty" >> "$WORK/bin/commit"; fi
}

# Whether the binary $1 reads the study's sweep.toml (a sweep edited since the binary was built
# may hold settings it does not know).
reads_sweep() { "$1" "$STUDY/sweep.toml" --list > /dev/null 2>&1; }

# A binary that reads the study's sweep.toml: BIN when set, else the study's own, else (the
# sweep gained settings newer than the binary the runs go on with) this checkout's; in LIST_BIN.
list_bin() {
  if [ -n "${BIN:-}" ]; then
    LIST_BIN=$BIN
  elif reads_sweep "$WORK/bin/rbc-sweep"; then
    LIST_BIN=$WORK/bin/rbc-sweep
  else
    echo "study.sh: $WORK/bin/rbc-sweep does not read $STUDY/sweep.toml (settings newer than the study's binary): reading it with this checkout's" >&2
    compile
    LIST_BIN=$BIN
  fi
}

# The runs of the sweep: "index run_id" per line.
runs() {
  "${LIST_BIN:-${BIN:-$WORK/bin/rbc-sweep}}" "$STUDY/sweep.toml" --list | awk 'NR > 1 { print $1, $2 }'
}

# The runs in the order they take the jobs: those named by --first (in its order), then the
# others in the sweep's order. A name that is no run of the sweep is refused.
ordered_runs() {
  local all name line
  all=$(runs)
  for name in ${FIRST//,/ }; do
    line=$(awk -v r="$name" '$2 == r' <<< "$all")
    [ -n "$line" ] || { echo "study.sh: --first: no run $name in $STUDY/sweep.toml" >&2; return 1; }
    echo "$line"
  done
  awk -v first=",$FIRST," 'index(first, "," $2 ",") == 0' <<< "$all"
}

# Process CPU seconds (user + system) of a running process and its children, from /proc.
cpu_of() {
  awk -v hz="$(getconf CLK_TCK)" '{ print ($14 + $15 + $16 + $17) / hz }' "/proc/$1/stat" 2>/dev/null || echo 0
}

# The CPU this machine has (/proc/cpuinfo's model name, commas made semicolons): the ledger's
# core-s depend on it (1.7-2x between the CPUs the studies have run on, solver/README.md "Session 30").
cpu_model() { awk -F': *' '/^model name/ { gsub(/,/, ";", $2); print $2; exit }' /proc/cpuinfo; }

# The study's ledger.csv with its header; a ledger written before session 30 (without the column
# cpu) gets the column, empty in its old rows (their CPU is unknown).
LEDGER_HEADER="saved_utc,commit,run_id,t_from_s,t_to_s,cpu_s,core_s_per_sim_ms,status,cpu"
ledger_init() {
  local f="$STUDY/ledger.csv"
  if [ ! -f "$f" ]; then echo "$LEDGER_HEADER" > "$f"
  elif [ "$(head -1 "$f")" != "$LEDGER_HEADER" ]; then
    awk -v h="$LEDGER_HEADER" 'NR == 1 { print h; next } { print $0 "," }' "$f" > "$f.tmp" && mv "$f.tmp" "$f"
  fi
}

# Whether a run's status says it has ended (nothing left to run).
ended() { case $1 in steady|periodic|unsteady|failed|overlaps-wall) return 0 ;; *) return 1 ;; esac; }

alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

case $CMD in
  resume)
    # a refill (a run ended and freed its job) keeps the binary the study runs with
    if [ -z "${STUDY_REFILL:-}" ] || [ ! -x "$WORK/bin/rbc-sweep" ]; then build; fi
    # a refill keeps the binary: a sweep edited since with settings it does not read waits for a resume
    if [ -n "${STUDY_REFILL:-}" ] && ! reads_sweep "$WORK/bin/rbc-sweep"; then
      echo "study.sh: refill: $WORK/bin/rbc-sweep does not read $STUDY/sweep.toml (settings newer than the study's binary): no run started; resume the study to take them" >&2
      exit 0
    fi
    mkdir -p "$WORK" "$STUDY/state"
    # one resume at a time (a refill and a resume by hand could start the same run twice)
    exec 9> "$WORK/.resume.lock"
    flock 9
    commit=$(tr -d '\n' < "$WORK/bin/commit")
    order=$(ordered_runs) || exit 2
    # runs already running count towards --jobs
    started=0
    while read -r index run; do alive "$WORK/$run.pid" && started=$((started + 1)); done < <(runs)
    while read -r index run; do
      [ -n "$run" ] || continue
      if alive "$WORK/$run.pid"; then echo "study.sh: $run is already running (pid $(cat "$WORK/$run.pid"))" >&2; continue; fi
      # a run that ended here since the last save (its stretch not yet saved): its work copy is
      # ahead of the saved state and stays for `save`
      if [ -f "$WORK/$run.h5" ] && [ -f "$WORK/$run.start" ]; then
        wstatus=$("$WORK/bin/rbc-sweep" --study-status "$WORK/$run.h5" --run "$run" --field status 2>/dev/null || echo absent)
        if ended "$wstatus"; then echo "study.sh: $run ended here ($wstatus) since the last save: kept for save" >&2; continue; fi
      fi
      # the saved state is the truth: a run that ended there has nothing to do, whether or not a
      # job is free; a run that waits or has nothing to do has no stretch to record at the next save
      state="absent 0"
      [ -f "$STUDY/state/$run.h5" ] && state=$("$WORK/bin/rbc-sweep" --study-status "$STUDY/state/$run.h5" --run "$run" --field status,t_s 2>/dev/null || echo "absent 0")
      read -r status t0 <<< "$state"
      if ended "$status"; then rm -f "$WORK/$run.start"; echo "study.sh: $run is $status at t = $t0 s: nothing to do" >&2; continue; fi
      if [ "$started" -ge "$JOBS" ]; then rm -f "$WORK/$run.start"; echo "study.sh: $run waits (--jobs $JOBS)" >&2; continue; fi
      # a work copy left from an earlier call is replaced by the saved state
      rm -f "$WORK/$run.h5" "$WORK/$run.h5.$run.ckpt" "$WORK/$run.h5.suspend"
      if [ -f "$STUDY/state/$run.h5" ]; then
        cp "$STUDY/state/$run.h5" "$WORK/$run.h5"
        [ -f "$STUDY/state/$run.h5.$run.ckpt" ] && cp "$STUDY/state/$run.h5.$run.ckpt" "$WORK/$run.h5.$run.ckpt"
      fi
      echo "$t0 $commit $(date -u +%Y-%m-%dT%H:%M:%SZ)" > "$WORK/$run.start"
      rm -f "$WORK/$run.cpu"
      (
        exec 9>&-
        nice -n 19 "$WORK/bin/rbc-sweep" "$STUDY/sweep.toml" --task "$index" --out "$WORK/$run.h5" >> "$WORK/$run.log" 2>&1 &
        echo $! > "$WORK/$run.pid"
        wait $! || true
        # the run's CPU seconds (its user + system time as this shell's child), for a run that
        # ends before `save` can read them from /proc
        # (`times` in this shell, not in a pipeline's subshell, which has no children)
        times > "$WORK/$run.times"
        awk 'NR == 2 { split($1, u, /[ms]/); split($2, s, /[ms]/); print u[1] * 60 + u[2] + s[1] * 60 + s[2] }' "$WORK/$run.times" > "$WORK/$run.cpu.tmp"
        mv "$WORK/$run.cpu.tmp" "$WORK/$run.cpu"
        # a run that ended on its own (not suspended by `save`) frees its job: the next waiting
        # run starts with the same binary
        st=$("$WORK/bin/rbc-sweep" --study-status "$WORK/$run.h5" --run "$run" --field status 2>/dev/null || echo absent)
        if ended "$st" && [ ! -e "$WORK/$run.h5.suspend" ]; then
          STUDY_REFILL=1 bash "$ROOT/scripts/study.sh" resume "$NAME" --jobs "$JOBS" ${FIRST_FLAG:+--first "$FIRST_FLAG"} >> "$WORK/refill.log" 2>&1 || true
        fi
      ) > /dev/null 2>&1 &
      sleep 1
      echo "study.sh: $run resumed from t = $t0 s (pid $(cat "$WORK/$run.pid"), log $WORK/$run.log)" >&2
      started=$((started + 1))
    done <<< "$order"
    ;;
  save)
    [ -d "$WORK" ] || { echo "study.sh: $WORK: nothing running or resumed here" >&2; exit 1; }
    list_bin
    mkdir -p "$STUDY/state"
    declare -A cpu
    while read -r index run; do
      if alive "$WORK/$run.pid"; then
        cpu[$run]=$(cpu_of "$(cat "$WORK/$run.pid")")
        touch "$WORK/$run.h5.suspend"
      fi
    done < <(runs)
    # each run stops at its next output sample (a few steps); at nice 19 on a busy machine that can take minutes
    for _ in $(seq 1 1800); do
      busy=0
      while read -r index run; do alive "$WORK/$run.pid" && busy=1 && cpu[$run]=$(cpu_of "$(cat "$WORK/$run.pid")"); done < <(runs)
      [ $busy = 0 ] && break
      sleep 1
    done
    [ $busy = 0 ] || { echo "study.sh: the runs did not stop within 30 minutes; nothing copied" >&2; exit 1; }
    ledger_init
    while read -r index run; do
      [ -f "$WORK/$run.h5" ] || continue
      [ -f "$WORK/$run.start" ] || continue
      read -r t0 commit _ < "$WORK/$run.start"
      out=$("$WORK/bin/rbc-sweep" --study-status "$WORK/$run.h5" --run "$run" --field status,t_s) || { echo "study.sh: $WORK/$run.h5 does not read back; state/ left unchanged" >&2; exit 1; }
      read -r status t1 <<< "$out"
      tmp="$STUDY/state/.$run.tmp"
      mkdir -p "$tmp"
      cp "$WORK/$run.h5" "$tmp/$run.h5"
      if [ -f "$WORK/$run.h5.$run.ckpt" ]; then cp "$WORK/$run.h5.$run.ckpt" "$tmp/$run.h5.$run.ckpt"; fi
      mv "$tmp/$run.h5" "$STUDY/state/$run.h5"
      if [ -f "$tmp/$run.h5.$run.ckpt" ]; then mv "$tmp/$run.h5.$run.ckpt" "$STUDY/state/$run.h5.$run.ckpt"; else rm -f "$STUDY/state/$run.h5.$run.ckpt"; fi
      rmdir "$tmp"
      c=${cpu[$run]:-}
      # a run that ended before this save: its CPU seconds as its wrapper recorded them
      [ -n "$c" ] || c=$(cat "$WORK/$run.cpu" 2>/dev/null || echo 0)
      rate=$(awk -v c="$c" -v a="$t0" -v b="$t1" 'BEGIN { d = (b - a) * 1e3; if (d > 0) printf "%.1f", c / d; else print "" }')
      echo "$(date -u +%Y-%m-%dT%H:%M:%SZ),$commit,$run,$t0,$t1,$c,$rate,$status,$(cpu_model)" >> "$STUDY/ledger.csv"
      # the next stretch starts here; a run that ended has none (no row again at the next save)
      if [ "$status" = running ]; then
        echo "$t1 $commit $(date -u +%Y-%m-%dT%H:%M:%SZ)" > "$WORK/$run.start"
      else
        rm -f "$WORK/$run.start"
      fi
      rm -f "$WORK/$run.h5.suspend" "$WORK/$run.pid" "$WORK/$run.cpu"
      echo "study.sh: saved $run at t = $t1 s ($status)" >&2
    done < <(runs)
    "$LIST_BIN" "$STUDY/sweep.toml" --study-status "$STUDY"/state/*.h5
    # the runs so far as a figure (lateral position and asphericity against time), kept as SVG
    if "$WORK/bin/rbc-sweep" --trajectories "$STUDY"/state/*.h5 --out "$WORK/figure" 2>/dev/null; then
      cp "$WORK/figure/trajectories.svg" "$STUDY/trajectories.svg"
    else
      echo "study.sh: the trajectories figure could not be drawn (state kept)" >&2
    fi
    # beside a sibling study of the same grid (named by the folder's file compare-with): the runs
    # both hold, drawn together into vs-SIBLING.svg (each labelled by its study)
    if [ -f "$STUDY/compare-with" ]; then
      other=$(head -n 1 "$STUDY/compare-with")
      pairs=()
      for f in "$STUDY"/state/*.h5; do
        o="$(dirname "$STUDY")/$other/state/$(basename "$f")"
        if [ -f "$o" ]; then pairs+=("$o" "$f"); fi
      done
      if [ ${#pairs[@]} -gt 0 ] && "$WORK/bin/rbc-sweep" --trajectories "${pairs[@]}" --out "$WORK/figure-vs" 2>/dev/null; then
        cp "$WORK/figure-vs/trajectories.svg" "$STUDY/vs-$other.svg"
      else
        echo "study.sh: the runs beside $other could not be drawn (state kept)" >&2
      fi
    fi
    publish
    echo "study.sh: commit examples/studies/$NAME/ (state/, ledger.csv) now; resume with: bash scripts/study.sh resume $NAME" >&2
    ;;
  status)
    [ -x "$WORK/bin/rbc-sweep" ] || build
    list_bin
    files=()
    unstarted=()
    while read -r index run; do
      # the work copy while its stretch is not saved (running, or ended since the last save), else the saved state
      if [ -f "$WORK/$run.h5" ] && { alive "$WORK/$run.pid" || [ -f "$WORK/$run.start" ]; }; then
        files+=("$WORK/$run.h5")
      elif [ -f "$STUDY/state/$run.h5" ]; then
        files+=("$STUDY/state/$run.h5")
      else
        unstarted+=("$run")
      fi
    done < <(runs)
    [ ${#files[@]} -gt 0 ] || { echo "study.sh: no run of $NAME has started" >&2; exit 0; }
    # while the study runs, an unfinished run without a process of its own waits for a job (--jobs)
    live=()
    while read -r index run; do alive "$WORK/$run.pid" && live+=("$run"); done < <(runs)
    table=$("$LIST_BIN" "$STUDY/sweep.toml" --study-status "${files[@]}" | awk -v live=" ${live[*]} " '
      BEGIN { active = live != "  " }
      { split($0, f, " [|] ") }
      active && f[2] == "running" && index(live, " " substr(f[1], 3) " ") == 0 { sub(/ [|] running [|] /, " | waiting | ") }
      { print }')
    echo "$table"
    # the runs that have not started: waiting for a job while the study runs, else not started
    word="not started"
    [ ${#live[@]} -eq 0 ] || word=waiting
    # a cell for each of the header's columns (the study's binary may be older than this
    # script): run, status, t, then `-`
    ncols=$(head -1 <<< "$table" | awk -F'|' '{ print NF - 2 }')
    for run in "${unstarted[@]}"; do
      row="| $run | $word | 0.00 |"
      for _ in $(seq 4 "$ncols"); do row+=" - |"; done
      echo "$row"
    done
    # on stderr, the runs whose cell stopped lying along the flow (turned over or folded) in the
    # saved state (`rbc-sweep events`; a running run's work copy is locked by its process): how
    # many times, the intervals and how the last one compares with the one before
    if compgen -G "$STUDY/state/*.h5" > /dev/null; then
      "$WORK/bin/rbc-sweep" events "$STUDY"/state/*.h5 2>&1 >/dev/null | grep -v ' 0 collapse(s)' | sed -e 's/^rbc-sweep: /study.sh: saved state: /' >&2 || true
    fi
    ;;
  reopen)
    [ -x "$WORK/bin/rbc-sweep" ] || build
    list_bin
    if alive "$WORK/$RUN_ARG.pid"; then echo "study.sh: $RUN_ARG is running: save first" >&2; exit 1; fi
    [ -f "$STUDY/state/$RUN_ARG.h5" ] || { echo "study.sh: $STUDY/state/$RUN_ARG.h5: no such run state" >&2; exit 1; }
    "$LIST_BIN" reopen "$STUDY/state/$RUN_ARG.h5" "$RUN_ARG" --sweep "$STUDY/sweep.toml"
    t=$("$WORK/bin/rbc-sweep" --study-status "$STUDY/state/$RUN_ARG.h5" --run "$RUN_ARG" --field t_s)
    ledger_init
    echo "$(date -u +%Y-%m-%dT%H:%M:%SZ),$(tr -d '\n' < "$WORK/bin/commit"),$RUN_ARG,$t,$t,0,,reopened,$(cpu_model)" >> "$STUDY/ledger.csv"
    publish
    echo "study.sh: $RUN_ARG reopened at t = $t s; commit examples/studies/$NAME/ and resume" >&2
    ;;
  relabel)
    # today's classification rule: this checkout's binary, not the one the runs go on with
    compile
    files=()
    while read -r index run; do
      if alive "$WORK/$run.pid"; then continue; fi
      [ -f "$STUDY/state/$run.h5" ] && files+=("$STUDY/state/$run.h5")
    done < <(runs)
    [ ${#files[@]} -gt 0 ] || { echo "study.sh: no saved run of $NAME is at rest" >&2; exit 0; }
    "$BIN" relabel "${files[@]}" --sweep "$STUDY/sweep.toml"
    publish
    echo "study.sh: commit examples/studies/$NAME/state/ now" >&2
    ;;
  *) usage ;;
esac

#!/usr/bin/env bash
# The stiff and extreme cases of the paper's channel scene at 2048 triangles (issue 11): each runs
# --ms simulated ms from rest or stops with a one-line diagnosis, never a NaN.
#
#   bash scripts/extreme_cases.sh [--ms 2] [--cases stiff-area,near-wall,lambda10,fast] [--walls exact|penalty]
#
# Every case is the study's scene (examples/studies/science-6p5/scene.toml: 2048 triangles,
# lambda 5, exact walls, Ewald 1e-4, ROS34PW2 with the dense mobility Jacobian at 2e-3 um; with
# --walls penalty the paper's-walls study's, examples/studies/science-6p5-penalty/scene.toml: the
# same with the paper's penalty walls, kappa_W = 1.9e7 N/m^3, RosW6S4 with the walls at 1e-4 um)
# with one change:
#   stiff-area  kappa_A = 1000 kappa_S (5e-3 N/m), a nearly area-incompressible membrane;
#   near-wall   the cell started with its rim 0.5 um from the side wall (centroid y = 1.6 um);
#   lambda10    viscosity ratio 10;
#   fast        the paper's highest velocity, 10.4 mm/s (mean flow 6.1 mm/s), at r_init 1.2 um.
# One thread each, one after the other; prints a Markdown table (outcome, simulated ms, steps,
# sharpest fold, core-s).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
MS=2
CASES=stiff-area,near-wall,lambda10,fast
WALLS=exact
while [ $# -gt 0 ]; do
  case $1 in
    --ms) MS=$2; shift 2 ;;
    --cases) CASES=$2; shift 2 ;;
    --walls) WALLS=$2; shift 2 ;;
    *) echo "usage: bash scripts/extreme_cases.sh [--ms 2] [--cases stiff-area,near-wall,lambda10,fast] [--walls exact|penalty]" >&2; exit 2 ;;
  esac
done
case $WALLS in
  exact) SCENE=$ROOT/examples/studies/science-6p5/scene.toml ;;
  penalty) SCENE=$ROOT/examples/studies/science-6p5-penalty/scene.toml ;;
  *) echo "extreme_cases: --walls must be exact or penalty, got $WALLS" >&2; exit 2 ;;
esac
WORK=${RBC_BENCH_WORK:-/tmp/rbc-extreme}/$WALLS
mkdir -p "$WORK"
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/work/target}
mkdir -p "$CARGO_TARGET_DIR" 2>/dev/null || export CARGO_TARGET_DIR=$ROOT/target
if ! pkg-config --exists hdf5 2>/dev/null; then bash scripts/setup.sh; fi
cargo build --release --quiet --bin rbc-simulate --bin rbc-sweep
BIN=$CARGO_TARGET_DIR/release
END_S=$(awk -v m="$MS" 'BEGIN { printf "%.6g", m * 1e-3 }')

echo "| case | outcome | simulated ms | steps (accepted) | sharpest fold (deg) | core-s |"
echo "|---|---|---|---|---|---|"
IFS=',' read -ra list <<< "$CASES"
for c in "${list[@]}"; do
  case $c in
    stiff-area) edit=('s/^kappa_a_n_m = .*/kappa_a_n_m = 5e-3/' 's/^position_um = .*/position_um = [0.0, 1.0490, 0.5828]/') ;;
    near-wall) edit=('s/^position_um = .*/position_um = [0.0, 1.6, 0.0]/') ;;
    lambda10) edit=('s/^lambda = .*/lambda = 10.0/' 's/^position_um = .*/position_um = [0.0, 1.0490, 0.5828]/') ;;
    fast) edit=('s/^mean_velocity_um_s = .*/mean_velocity_um_s = 6100.0/' 's/^position_um = .*/position_um = [0.0, 1.0490, 0.5828]/') ;;
    *) echo "extreme_cases: unknown case $c" >&2; exit 2 ;;
  esac
  args=()
  for e in "${edit[@]}"; do args+=(-e "$e"); done
  sed "${args[@]}" -e "s/^end_s = .*/end_s = $END_S/" -e "s/^name = .*/name = \"$c\"/" "$SCENE" > "$WORK/$c.toml"
  # every edit must have matched a line of the scene
  for e in "${edit[@]}"; do
    key=$(sed -E 's|^s/\^([a-z_]+) = .*|\1|' <<< "$e")
    grep -q "^$key = " "$SCENE" || { echo "extreme_cases: $SCENE has no line '$key = '" >&2; exit 1; }
  done
  rm -f "$WORK/$c.h5" "$WORK/$c.h5".*.ckpt
  status=0
  /usr/bin/time -f "%U %S" -o "$WORK/$c.time" env RAYON_NUM_THREADS=1 "$BIN/rbc-simulate" "$WORK/$c.toml" --out "$WORK/$c.h5" > "$WORK/$c.log" 2>&1 || status=$?
  cpu=$(awk '{ printf "%.0f", $1 + $2 }' "$WORK/$c.time" 2>/dev/null || echo "?")
  read -r st t fold <<< "$("$BIN/rbc-sweep" --study-status "$WORK/$c.h5" --run "$c" --field status,t_s,sharpest_fold_deg 2>/dev/null || echo "none 0 0")"
  steps=$(grep -o '([0-9]* steps' "$WORK/$c.log" | tr -dc '0-9' || true)
  if [ "$status" = 0 ]; then
    outcome="ran $MS ms"
  else
    outcome="stopped: $(grep -v '^\s*$' "$WORK/$c.log" | tail -1 | tr '|' '/')"
  fi
  ms=$(awk -v t="$t" 'BEGIN { printf "%.3f", t * 1e3 }')
  printf "| %s | %s | %s | %s | %.0f | %s |\n" "$c" "$outcome" "$ms" "${steps:--}" "$fold" "$cpu"
done

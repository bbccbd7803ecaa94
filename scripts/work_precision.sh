#!/usr/bin/env bash
# The work-precision table of the paper's channel scene at 2048 triangles (issue 11): the science
# observables' largest deviation from a tight reference against the cost, for the paper's
# integrator (bs23) and the W-method the studies use (ROS34PW2 with the dense mobility Jacobian)
# at several tolerances, this checkout's code, in the issue's two 5 ms windows (from rest and
# from the r_init 1.2 um run's shape at 20 ms).
#
#   bash scripts/work_precision.sh [--ms 5] [--cases rest,mid] [--jobs 2]
#
# The reference is bs23 at atol 1e-5 um (the paper's 4e-5 is a row of the table). Runs go
# --jobs at a time, one thread each, each timed as its own process (scripts/bench_speed.sh
# --no-pair); the tables are `rbc-bench compare`'s.
set -euo pipefail
cd "$(dirname "$0")/.."
ARGS=()
while [ $# -gt 0 ]; do
  case $1 in
    --ms|--cases|--jobs) ARGS+=("$1" "$2"); shift 2 ;;
    *) echo "usage: bash scripts/work_precision.sh [--ms 5] [--cases rest,mid] [--jobs 2]" >&2; exit 2 ;;
  esac
done
settings=()
for atol in 1e-4 4e-5 2e-5; do settings+=(--setting "bs23@$atol:scheme=\"bs23\",atol_um=$atol"); done
for atol in 8e-3 4e-3 2e-3 1e-3 5e-4; do settings+=(--setting "ros34pw2-mobility@$atol:scheme=\"ros34pw2-mobility\",atol_um=$atol"); done
settings+=(--setting 'ros34pw2-local@1e-3:scheme="ros34pw2-local",atol_um=1e-3,h_max_s=')
exec bash scripts/bench_speed.sh --no-pair --jobs 2 --reference 'scheme="bs23",atol_um=1e-5' "${settings[@]}" "${ARGS[@]}"

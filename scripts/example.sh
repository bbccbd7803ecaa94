#!/usr/bin/env bash
# The main job on the shipped example data, on a fresh machine:
# installs what is missing, builds, analyses examples/frames/ and, when the
# example simulation results are present, predicts the croissant fraction.
# Outputs: rbc-analysis/ and rbc-prediction/ in the current folder.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
bash "$here/scripts/setup.sh"
# absolute: the build runs in the checkout, the binaries from here
export CARGO_TARGET_DIR="$(realpath -m "${CARGO_TARGET_DIR:-$here/target}")"
# from the checkout's folder: cargo reads .cargo/config.toml (target-cpu=native) from the folder it
# runs in, and a binary built without it runs the solver ~3.5x slower (src/build_cpu.rs)
(cd "$here" && cargo build --release --bins)
bin="$CARGO_TARGET_DIR/release"
"$bin/rbc-analyze" "$here/examples/frames" --out rbc-analysis
if [ -f "$here/examples/results.h5" ]; then
  "$bin/rbc-predict" --sims "$here/examples/results.h5" --entry rbc-analysis/entry.csv \
    --observed rbc-analysis/summary.csv --out rbc-prediction
fi
echo "example: outputs in $(pwd)/rbc-analysis$([ -f "$here/examples/results.h5" ] && echo " and $(pwd)/rbc-prediction")"

#!/usr/bin/env bash
# Regenerate the shipped example outputs with the current code (examples/README.md lists them and
# the test that says when each is stale).
#
#   bash scripts/examples.sh results   # examples/results.h5: the ended runs of the study
#                                      # examples/studies/science-6p5 merged (seconds), and its .xmf files
#   bash scripts/examples.sh demo      # examples/demo-results.h5 (the free-space demo sweep, ~1 min on 2 cores) and its .xmf files
#   bash scripts/examples.sh frames    # examples/frames/ (the synthesiser's eight recordings, seconds)
#   bash scripts/examples.sh all       # all three
#
# A new results file is written beside the old one and moved over it only when it is complete
# (rbc-sweep would otherwise resume the old file and keep its runs).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
what="${1:-all}"
case "$what" in results | demo | frames | all) ;; *) echo "usage: $0 results|demo|frames|all" >&2; exit 2 ;; esac
# absolute: the build runs in the checkout
export CARGO_TARGET_DIR="$(realpath -m "${CARGO_TARGET_DIR:-$here/target}")"
bin="$CARGO_TARGET_DIR/release"
# RBC_SWEEP_BIN: an rbc-sweep binary to merge with instead of building one (scripts/study.sh
# passes the study's own after a save)
sweep="${RBC_SWEEP_BIN:-}"
if [ -z "$sweep" ] || [ "$what" != results ]; then
  # from the checkout's folder, so that cargo reads .cargo/config.toml (src/build_cpu.rs)
  (cd "$here" && cargo build --release -p rbc --bin rbc-sweep --bin rbc-synth)
fi
sweep="${sweep:-$bin/rbc-sweep}"

tmp="$(mktemp -d "$here/examples/.regenerate.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
if [ "$what" = results ] || [ "$what" = all ]; then
  # the study's runs that have ended (steady, periodic or unsteady); running ones stay out
  state="$here/examples/studies/science-6p5/state"
  ended=()
  for f in "$state"/*.h5; do
    run="$(basename "$f" .h5)"
    status="$("$sweep" --study-status "$f" --run "$run" --field status)"
    case "$status" in steady | periodic | unsteady) ended+=("$f") ;; esac
  done
  [ "${#ended[@]}" -gt 0 ] || { echo "examples.sh: no ended run in $state" >&2; exit 1; }
  "$sweep" merge "${ended[@]}" --out "$tmp/results.h5"
  mv "$tmp/results.h5" "$here/examples/results.h5"
  rm -f "$here"/examples/results.*.xmf
  "$sweep" xdmf "$here/examples/results.h5"
fi
if [ "$what" = demo ] || [ "$what" = all ]; then
  "$sweep" "$here/examples/sweeps/demo-poiseuille.toml" --out "$tmp/demo-results.h5" --jobs 2
  mv "$tmp/demo-results.h5" "$here/examples/demo-results.h5"
  rm -f "$here"/examples/demo-results.*.xmf
  "$sweep" xdmf "$here/examples/demo-results.h5"
fi
if [ "$what" = frames ] || [ "$what" = all ]; then
  "$bin/rbc-synth" --examples "$here/examples/frames"
fi

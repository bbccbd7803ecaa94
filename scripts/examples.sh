#!/usr/bin/env bash
# Regenerate the shipped example outputs with the current code (examples/README.md lists them and
# the test that says when each is stale).
#
#   bash scripts/examples.sh results   # examples/results.h5 (the demo sweep, ~1 min on 2 cores) and its .xmf files
#   bash scripts/examples.sh frames    # examples/frames/ (the synthesiser's six recordings, seconds)
#   bash scripts/examples.sh all       # both
#
# The new results file is written beside the old one and moved over it only when the sweep has
# finished (rbc-sweep would otherwise resume the old file and keep its runs).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
what="${1:-all}"
case "$what" in results | frames | all) ;; *) echo "usage: $0 results|frames|all" >&2; exit 2 ;; esac
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$here/target}"
cargo build --manifest-path "$here/Cargo.toml" --release -p rbc --bin rbc-sweep --bin rbc-synth
bin="$CARGO_TARGET_DIR/release"

if [ "$what" = results ] || [ "$what" = all ]; then
  tmp="$(mktemp -d "$here/examples/.regenerate.XXXXXX")"
  trap 'rm -rf "$tmp"' EXIT
  "$bin/rbc-sweep" "$here/examples/sweeps/demo-poiseuille.toml" --out "$tmp/results.h5" --jobs 2
  mv "$tmp/results.h5" "$here/examples/results.h5"
  rm -f "$here"/examples/results.*.xmf
  "$bin/rbc-sweep" --xdmf "$here/examples/results.h5"
fi
if [ "$what" = frames ] || [ "$what" = all ]; then
  "$bin/rbc-synth" --examples "$here/examples/frames"
fi

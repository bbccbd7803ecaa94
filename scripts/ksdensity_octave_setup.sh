#!/usr/bin/env bash
# Extract GNU Octave statistics' ksdensity (and the private kernel helpers it calls) from a git
# clone of github.com/gnu-octave/statistics into OUT_DIR, for
#   python3 scripts/ksdensity_reference.py --octave OUT_DIR
# Only these four files are put on Octave's path, so the package's newer versions of core
# functions do not shadow Octave's own (runs under Debian 12's Octave 7.3 with octave-statistics 1.5.3,
# which has no ksdensity of its own).
# Usage: scripts/ksdensity_octave_setup.sh GIT_DIR OUT_DIR [COMMIT]   (COMMIT default c2e3c2b6, 2026-08-23)
set -euo pipefail
git_dir=$1
out=$2
commit=${3:-c2e3c2b6}
mkdir -p "$out/private"
src=inst/Descriptive_Statistics
git --git-dir="$git_dir" show "$commit:$src/ksdensity.m" > "$out/ksdensity.m"
for f in kernelpdf kernelcdf kernelscale; do
  git --git-dir="$git_dir" show "$commit:$src/private/$f.m" > "$out/private/$f.m"
done
echo "ksdensity from gnu-octave/statistics@$commit in $out"

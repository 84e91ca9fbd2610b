#!/bin/sh
# The seed's 10,000-run leveling experiment (navtwin level-mc defaults, seed 1) as a run
# folder with its report: the pitch and roll error histograms of every method, each with
# the normal density of its RMS (figures/pitch_histogram.svg, roll_histogram.svg; the first
# is the one docs/leveling-results.md shows).
# Usage: docs/leveling/histograms.sh [NAVTWIN [OUT_DIR]]   (defaults: build/bin/navtwin, a
#   new temporary folder). Nothing is written into the repository; to refresh the
#   documentation, copy OUT_DIR/figures/pitch_histogram.svg to docs/leveling/.
set -eu
navtwin=${1:-build/bin/navtwin}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
"$navtwin" level-mc --runs 10000 --seed 1 --threads 2 --out "$out/run"
"$navtwin" report "$out/run" --out "$out/report.html" --figures_dir "$out/figures"
echo "report: $out/report.html; figures: $out/figures/"

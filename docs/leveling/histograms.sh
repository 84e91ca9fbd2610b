#!/bin/sh
# Re-makes docs/leveling/pitch_error_*.png: the seed's 10,000-run experiment (navtwin
# level-mc defaults, seed 1) with every run's errors written to a temporary CSV, then the
# histograms of histograms.gp.
# Usage: docs/leveling/histograms.sh [NAVTWIN_BINARY]   (default: build/bin/navtwin)
set -eu
navtwin=${1:-build/bin/navtwin}
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$navtwin" level-mc --runs 10000 --seed 1 --threads 2 --errors_csv "$tmp/errors.csv"
gnuplot -e "csv='$tmp/errors.csv'; outdir='$here'" "$here/histograms.gp"
ls -l "$here"/pitch_error_*.png

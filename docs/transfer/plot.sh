#!/bin/sh
# The slave attitude error of the transfer-alignment methods (order1, order2, batch) against
# the transfer delay, 0 to 500 ms in steps of 50 ms, seed 1, the simulated master's delay
# overridden with --delay_s: one `navtwin transfer-align --out` run folder per delay, then one
# `navtwin report` over all of them. Its figure "Slave attitude RMS against the true delay"
# (figures/attitude_rms_vs_delay.svg) is the one docs/transfer-alignment.md shows; the page
# also overlays every run's misalignment and delay convergence. Prints the table drawn.
# Usage: docs/transfer/plot.sh [NAVTWIN [SCENARIO [OUT_DIR]]]
#   defaults: build/bin/navtwin, transfer-alignment-high-maneuver, a new temporary folder.
#   Nothing is written into the repository; to refresh the documentation, copy
#   OUT_DIR/figures/attitude_rms_vs_delay.svg to docs/transfer/error_vs_delay.svg (the
#   preset) or error_vs_delay_seed_regime.svg (SCENARIO docs/transfer/seed-regime.yaml).
set -eu
navtwin=${1:-build/bin/navtwin}
scenario=${2:-transfer-alignment-high-maneuver}
out=${3:-$(mktemp -d)}
mkdir -p "$out"
dirs=""
for ms in 0 50 100 150 200 250 300 350 400 450 500; do
  delay=$(awk -v ms="$ms" 'BEGIN { printf "%.3f", ms / 1000 }')
  run=$(printf '%s/delay_%03dms' "$out" "$ms")
  echo "transfer plot: delay $ms ms" >&2
  "$navtwin" transfer-align --scenario "$scenario" --seed 1 --delay_s "$delay" --method all --out "$run" \
    2> "$out/stderr.txt" > /dev/null || { cat "$out/stderr.txt" >&2; exit 1; }
  dirs="$dirs $run"
done
# shellcheck disable=SC2086  # the run folders, one word each
"$navtwin" report $dirs --out "$out/report.html" --figures_dir "$out/figures"
printf '%-10s %-7s %9s %9s %9s %10s %10s\n' delay_ms method roll_rms pitch_rms head_rms delay_est delay_sig
for run in $dirs; do
  jq -r --arg run "$(basename "$run")" '.methods[] | [$run, .method, .roll_rms_mrad, .pitch_rms_mrad,
      .heading_rms_mrad, (.delay_est_s * 1000), (.delay_sigma_s * 1000)]
      | map(if . == null then "nan" else tostring end) | join(" ")' "$run/summary.json"
done | awk '{ printf "%-10s %-7s %9.4g %9.4g %9.4g %10.4g %10.3g\n", substr($1, 7), $2, $3, $4, $5, $6, $7 }'
echo "report: $out/report.html; figures: $out/figures/"

#!/bin/sh
# Re-makes docs/transfer/error_vs_delay.png: the slave attitude error of the three methods
# of issue 6 (order1, order2, batch) against the transfer delay, 0 to 500 ms in steps of
# 50 ms, on the preset transfer-alignment-high-maneuver (seed 1; the delay of the simulated
# master overridden with --delay_s). Top: heading RMS; bottom: roll and pitch RMS (mrad,
# after settle_s). Prints the table the figure is drawn from (also the delay estimates).
# Usage: docs/transfer/plot.sh [NAVTWIN_BINARY [SCENARIO [TAG]]]
#   (defaults: build/bin/navtwin, transfer-alignment-high-maneuver, no tag; the figure is
#   error_vs_delay${TAG}.png, e.g. docs/transfer/plot.sh build/bin/navtwin
#   docs/transfer/seed-regime.yaml _seed_regime)
set -eu
navtwin=${1:-build/bin/navtwin}
scenario=${2:-transfer-alignment-high-maneuver}
tag=${3:-}
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
data="$tmp/error_vs_delay.dat"
printf '# delay_ms method roll_rms_mrad pitch_rms_mrad heading_rms_mrad roll_max_mrad pitch_max_mrad heading_max_mrad delay_est_ms delay_sigma_ms misalignment_error_mrad\n' > "$data"
for ms in 0 50 100 150 200 250 300 350 400 450 500; do
  delay=$(awk -v ms="$ms" 'BEGIN { printf "%.3f", ms / 1000 }')
  echo "error_vs_delay: delay $ms ms" >&2
  "$navtwin" transfer-align --scenario "$scenario" --seed 1 --delay_s "$delay" \
    --method all --format=json 2> "$tmp/stderr" > "$tmp/run.json" || { cat "$tmp/stderr" >&2; exit 1; }
  # One line per method; null (unknown) becomes NaN, which gnuplot skips.
  jq -r --arg ms "$ms" '.[] | [$ms, .method, .roll_rms_mrad, .pitch_rms_mrad, .heading_rms_mrad,
      .roll_max_mrad, .pitch_max_mrad, .heading_max_mrad, (.delay_est_s * 1000), (.delay_sigma_s * 1000),
      .misalignment_error_mrad] | map(if . == null then "NaN" else tostring end) | join(" ")' \
    "$tmp/run.json" >> "$data"
done
for m in order1 order2 batch; do
  awk -v m="$m" '$2 == m' "$data" > "$tmp/$m.dat"
done
gnuplot -e "dir='$tmp'; outdir='$here'; tag='$tag'; scenario='$(basename "$scenario" .yaml)'" "$here/error_vs_delay.gp"
awk 'NR == 1 { print; next } { printf "%s %s", $1, $2; for (i = 3; i <= NF; ++i) printf " %.4g", $i; printf "\n" }' "$data" |
  column -t
ls -l "$here/error_vs_delay$tag.png"

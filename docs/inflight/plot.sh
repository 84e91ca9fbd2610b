#!/bin/sh
# The heading error of the three in-flight alignment methods (distance, kalman, batch) against
# the distance flown on the preset inflight-mach07-south (seed 1), as run folders and one
# `navtwin report` over them: `clean` (no outliers), `outliers` (1 % GPS outliers of 200 m)
# and `outliers_noloss` (the batch on the same data without its robust loss). The report's
# heading-error figures are the ones docs/inflight-alignment.md shows; clean.html is the
# clean run's own page.
# Usage: docs/inflight/plot.sh [NAVTWIN [OUT_DIR]]   (defaults: build/bin/navtwin, a new
#   temporary folder). Nothing is written into the repository; to refresh the documentation,
#   copy OUT_DIR/figures_clean/heading_error.svg to docs/inflight/heading_vs_distance.svg,
#   OUT_DIR/figures_clean/heading_error_second_half.svg to heading_vs_distance_second_half.svg
#   and OUT_DIR/figures/heading_error_second_half.svg to heading_vs_distance_outliers.svg.
set -eu
navtwin=${1:-build/bin/navtwin}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
common="inflight-align --scenario inflight-mach07-south --seed 1"
"$navtwin" $common --method all --out "$out/clean" > /dev/null
"$navtwin" $common --method all --outlier_fraction 0.01 --outlier_m 200 --out "$out/outliers" > /dev/null
printf 'batch:\n  loss: none\n' > "$out/no_loss.yaml"
"$navtwin" $common --method batch --outlier_fraction 0.01 --outlier_m 200 --config "$out/no_loss.yaml" \
  --out "$out/outliers_noloss" > /dev/null
"$navtwin" report "$out/clean" --out "$out/clean.html" --figures_dir "$out/figures_clean"
"$navtwin" report "$out/clean" "$out/outliers" "$out/outliers_noloss" --out "$out/report.html" \
  --figures_dir "$out/figures"
echo "report: $out/report.html (clean run alone: $out/clean.html); figures: $out/figures/, $out/figures_clean/"

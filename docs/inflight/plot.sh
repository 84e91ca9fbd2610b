#!/bin/sh
# Re-makes docs/inflight/heading_vs_distance*.png: the heading error of the three methods
# of issue 7 against the distance flown on the preset inflight-mach07-south (seed 1),
# without and with 1 % GPS outliers of 200 m (batch with and without its robust loss).
# Usage: docs/inflight/plot.sh [NAVTWIN_BINARY]   (default: build/bin/navtwin)
set -eu
navtwin=${1:-build/bin/navtwin}
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for m in distance kalman batch; do
  "$navtwin" inflight-align --scenario inflight-mach07-south --seed 1 --method $m \
    --track_csv "$tmp/clean_$m.csv" > /dev/null
  "$navtwin" inflight-align --scenario inflight-mach07-south --seed 1 --method $m \
    --outlier_fraction 0.01 --outlier_m 200 --track_csv "$tmp/outliers_$m.csv" > /dev/null
done
printf 'batch:\n  loss: none\n' > "$tmp/no_loss.yaml"
"$navtwin" inflight-align --scenario inflight-mach07-south --seed 1 --method batch \
  --outlier_fraction 0.01 --outlier_m 200 --config "$tmp/no_loss.yaml" \
  --track_csv "$tmp/outliers_batch_noloss.csv" > /dev/null
gnuplot -e "dir='$tmp'; outdir='$here'" "$here/heading_vs_distance.gp"
ls -l "$here"/heading_vs_distance*.png

#!/bin/sh
# Transfer-alignment methods over seeds and delays: one `navtwin transfer-align --method all
# --format=json` per (seed, delay), one line per method into a table of runs, then the
# statistics per (delay, method) over the seeds: mean of the per-run attitude RMS (roll,
# pitch, heading, mrad), mean |delay error| and the largest (ms), mean delay sigma (ms), and
# the average NEES of (misalignment, delay) with its two-sided 95 % chi-square bounds for
# the run count (4 degrees of freedom per run; Wilson-Hilferty). docs/transfer-alignment.md,
# "Delayed-state fusion", shows the tables.
# Usage: docs/transfer/sweep.sh NAVTWIN SCENARIO "SEEDS" "DELAYS_MS" OUT.tsv
#   e.g.  docs/transfer/sweep.sh build/bin/navtwin transfer-alignment-high-maneuver \
#           "$(seq 1 20)" "0 100 200 300 400 450 500" /tmp/sweep.tsv
#        docs/transfer/sweep.sh --summary /tmp/sweep.tsv [more.tsv ...]
set -eu
summary() {
  awk -F'\t' '
    function chi2q(k, z) { return k * (1 - 2 / (9 * k) + z * sqrt(2 / (9 * k))) ^ 3 }
    { key = $1 "\t" $2; if (!(key in n)) order[++m] = key
      n[key]++; r[key] += $4; p[key] += $5; h[key] += $6
      e = ($7 - $8) * 1000; if (e < 0) e = -e; de[key] += e; if (e > dm[key]) dm[key] = e
      ds[key] += $9 * 1000
      if ($10 != "null") { nees[key] += $10; nn[key]++ } }
    END {
      printf "%-8s %-8s %4s %8s %8s %8s %9s %9s %9s %8s %17s\n", "delay_ms", "method", "runs", "roll", "pitch",
             "heading", "|dtau|ms", "max|dtau|", "sigma_ms", "ANEES", "95% bounds"
      for (i = 1; i <= m; i++) {
        key = order[i]; split(key, kk, "\t"); k = n[key]
        lo = "-"; hi = "-"; an = "-"
        if (nn[key] > 0) { dof = 4 * nn[key]; an = sprintf("%.2f", nees[key] / nn[key])
          lo = sprintf("%.2f", chi2q(dof, -1.959964) / nn[key]); hi = sprintf("%.2f", chi2q(dof, 1.959964) / nn[key]) }
        printf "%-8s %-8s %4d %8.3f %8.3f %8.3f %9.4f %9.4f %9.4f %8s %8s-%-8s\n", kk[1], kk[2], k, r[key] / k,
               p[key] / k, h[key] / k, de[key] / k, dm[key], ds[key] / k, an, lo, hi
      } }' "$@"
}
if [ "${1:-}" = "--summary" ]; then
  shift
  summary "$@"
  exit 0
fi
navtwin=$1 scenario=$2 seeds=$3 delays=$4 out=$5
: > "$out"
for ms in $delays; do
  delay=$(awk -v ms="$ms" 'BEGIN { printf "%.3f", ms / 1000 }')
  for seed in $seeds; do
    echo "transfer sweep: delay $ms ms, seed $seed" >&2
    "$navtwin" transfer-align --scenario "$scenario" --seed "$seed" --delay_s "$delay" --method all --format=json \
      2> /dev/null |
      jq -r --arg ms "$ms" --arg seed "$seed" '.[] | [$ms, .method, $seed, .roll_rms_mrad, .pitch_rms_mrad,
          .heading_rms_mrad, .delay_est_s, .delay_true_s, .delay_sigma_s, .nees_misalignment_delay]
          | map(if . == null then "null" else tostring end) | join("\t")' >> "$out"
  done
done
summary "$out"

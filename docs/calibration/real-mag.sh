#!/usr/bin/env bash
# The magnetometer calibrations on the recorded data (docs/calibration-magnetometer.md,
# "Real magnetometers"): calibrate-mag --format=json with the ellipsoid, planar and
# bidirectional methods on every Xsens DOT raw file with magnetometer columns in
# ansfl-quadrotor/StraightLine/RAW (and Horizontal/RAW if present) and on px4-ulog/*.ulg.
# One markdown table row per (file, method): samples, what the spread is of, the spread
# before, and the spread after or the refusal reason.
#
# usage: docs/calibration/real-mag.sh [NAVTWIN] [DATA_DIR]
#   NAVTWIN   the navtwin binary (default build/bin/navtwin)
#   DATA_DIR  the shared data (default $NAVTWIN_DATA, else ../shared/data)
# Needs jq.
set -euo pipefail

navtwin=${1:-build/bin/navtwin}
data=${2:-${NAVTWIN_DATA:-../shared/data}}
[[ -x $navtwin ]] || { echo "real-mag.sh: no navtwin binary at $navtwin" >&2; exit 2; }
[[ -d $data ]] || { echo "real-mag.sh: no data directory $data" >&2; exit 2; }
command -v jq >/dev/null || { echo "real-mag.sh: jq is needed" >&2; exit 2; }

files=()
for dir in "$data/ansfl-quadrotor/StraightLine/RAW" "$data/ansfl-quadrotor/Horizontal/RAW"; do
  [[ -d $dir ]] || continue
  for f in "$dir"/Xsens_DOT*.csv; do
    [[ -e $f ]] || continue
    head -n 1 "$f" | grep -q 'Mag_X' && files+=("$f")  # DOT4 records no magnetometer
  done
done
for f in "$data"/px4-ulog/*.ulg; do [[ -e $f ]] && files+=("$f"); done
[[ ${#files[@]} -gt 0 ]] || { echo "real-mag.sh: no magnetometer files under $data" >&2; exit 1; }

err=$(mktemp)
trap 'rm -f "$err"' EXIT
echo "| File | Method | Samples | Spread of | Before [uT] | After [uT] or refusal |"
echo "|---|---|---|---|---|---|"
for f in "${files[@]}"; do
  name=${f#"$data"/}
  for method in ellipsoid planar bidirectional; do
    if out=$("$navtwin" calibrate-mag --mag "$f" --method "$method" --format=json 2>"$err"); then
      jq -r --arg f "$name" --arg m "$method" \
        '"| \($f) | \($m) | \(.samples) | \(.spread_of) | \(.field_spread_before_uT * 1000 | round / 1000) | \(.field_spread_after_uT * 1000 | round / 1000) |"' \
        <<<"$out"
    else
      # "navtwin calibrate-mag: refused (N samples, |m| spread X uT): reason"
      line=$(grep -m1 'refused\|error' "$err" || true)
      if [[ $line =~ refused\ \(([0-9]+)\ samples,\ \|m\|\ spread\ ([^ ]+)\ uT\):\ (.*)$ ]]; then
        echo "| $name | $method | ${BASH_REMATCH[1]} | \\|m\\| | ${BASH_REMATCH[2]} | refused: ${BASH_REMATCH[3]//|/\\|} |"
      else
        echo "| $name | $method | - | - | - | failed: ${line//|/\\|} |"
      fi
    fi
  done
done

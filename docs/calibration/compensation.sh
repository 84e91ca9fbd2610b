#!/bin/sh
# Does an IMU calibration pay off in navigation? For each seed: calibrate a MEMS IMU with
# large fixed errors on a simulated 14-position table (table-mems.yaml), then navigate a
# GNSS/INS manoeuvre flight of the same IMU (nav-mems-fixed-errors.yaml) with 30 s GNSS
# outages every 90 s: raw with the data-sheet configuration, with --calibration and the
# configuration of the residual errors, and (no_file) that configuration without the
# calibration file. Prints smooth's error lines (filter, RTS, batch).
# Usage: docs/calibration/compensation.sh [NAVTWIN_BINARY] [SEEDS]
#        (defaults: build/bin/navtwin, "1 2 3")
set -eu
navtwin=${1:-build/bin/navtwin}
seeds=${2:-1 2 3}
here=$(cd "$(dirname "$0")" && pwd)
[ -x "$navtwin" ] || { echo "compensation.sh: no navtwin binary at $navtwin" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-5s %-11s %s\n' seed run "method   horiz [m]   vert [m]  vel [m/s] roll [deg] pitch[deg]  yaw [deg] drift H[m] drift V[m]    run [s]"
for seed in $seeds; do
  d="$tmp/seed$seed"
  mkdir -p "$d/table" "$d/nav"
  "$navtwin" simulate --scenario "$here/table-mems.yaml" --seed "$seed" --out "$d/table" > /dev/null 2>&1
  # The calibration record: the IMU file, the site and the table schedule of the scenario.
  { printf 'imu: table/imu.txt\nlatitude_deg: 37.45\nheight_m: 300\n'
    awk '/^trajectory:/ {on = 1; print; next} on && /^[^ ]/ {on = 0} on' "$here/table-mems.yaml"
  } > "$d/record.yaml"
  "$navtwin" calibrate-imu --rig multiposition --data "$d/record.yaml" --out "$d/calibration.yaml" > /dev/null
  "$navtwin" simulate --scenario "$here/nav-mems-fixed-errors.yaml" --seed "$seed" --out "$d/nav" > /dev/null 2>&1
  cp "$here/navtwin-datasheet.yaml" "$here/navtwin-calibrated.yaml" "$d/nav/"
  for run in raw calibrated no_file; do
    case $run in
      raw) extra="--config $d/nav/navtwin-datasheet.yaml" ;;
      calibrated) extra="--config $d/nav/navtwin-calibrated.yaml --calibration $d/calibration.yaml" ;;
      no_file) extra="--config $d/nav/navtwin-calibrated.yaml" ;;  # the residual-error configuration alone
    esac
    # shellcheck disable=SC2086
    "$navtwin" smooth --imu "$d/nav/imu.txt" --gnss "$d/nav/gnss.txt" --truth "$d/nav/truth.nav" \
      --out "$d/out_$run" --outage_start_s 60 --outage_len_s 30 --outage_period_s 90 $extra 2>/dev/null |
      awk -v s="$seed" -v r="$run" '/^(filter|rts|batch) / {printf "%-5s %-11s %s\n", s, r, $0}'
  done
done

#!/bin/sh
# Outage drift of the simulated MEMS car (preset mems-car-odometer, docs/scenarios.md) with
# 60 s GNSS outages every 180 s: filter, RTS and batch without vehicle aiding, with the
# non-holonomic constraint, and with NHC + the wheel odometer. The configuration is
# data/configs/mems-car.yaml (the IMU's specification values); the vehicle aiding is
# switched on from the command line. Prints smooth's error lines with the seed and the run.
# Usage: docs/vehicle/outage-drift.sh [NAVTWIN_BINARY] [SEEDS]   (defaults: build/bin/navtwin, "1 2 3")
set -eu
navtwin=${1:-build/bin/navtwin}
seeds=${2:-1 2 3}
here=$(cd "$(dirname "$0")" && pwd)
config="$here/../../data/configs/mems-car.yaml"
[ -x "$navtwin" ] || { echo "outage-drift.sh: no navtwin binary at $navtwin" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-5s %-9s %s\n' seed run "method   horiz [m]   vert [m]  vel [m/s] roll [deg] pitch[deg]  yaw [deg] drift H[m] drift V[m]    run [s]"
for seed in $seeds; do
  d="$tmp/seed$seed"
  "$navtwin" simulate --scenario mems-car-odometer --seed "$seed" --out "$d" > /dev/null 2>&1
  cp "$config" "$d/"
  for run in free nhc nhc_odo; do
    case $run in
      free) extra="" ;;
      nhc) extra="--nhc" ;;
      nhc_odo) extra="--nhc --odometer $d/odometer.csv" ;;
    esac
    # shellcheck disable=SC2086
    "$navtwin" smooth --imu "$d/imu.txt" --gnss "$d/gnss.txt" --config "$d/mems-car.yaml" --truth "$d/truth.nav" \
      --out "$d/$run" --outage_start_s 120 --outage_len_s 60 --outage_period_s 180 $extra 2> /dev/null |
      awk -v s="$seed" -v r="$run" '/^(filter|rts|batch) / {printf "%-5s %-9s %s\n", s, r, $0}'
  done
done

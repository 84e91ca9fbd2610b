#!/usr/bin/env bash
# A compiler launcher that measures each compile: appends "<seconds> <object>" to the file
# in $NAVTWIN_COMPILE_TIMES (default: compile-times.txt in the working folder of the build).
# Usage (docs/building.md):
#   cmake -S . -B build -DCMAKE_CXX_COMPILER_LAUNCHER="$PWD/cmake/compile-timer.sh"
#   NAVTWIN_COMPILE_TIMES=$PWD/times.txt cmake --build build -j2
#   sort -rn times.txt | head -15
set -u
start_ns=$(date +%s%N)
"$@"
status=$?
end_ns=$(date +%s%N)
object=""
previous=""
for arg in "$@"; do
  [ "$previous" = "-o" ] && object=$arg
  previous=$arg
done
printf '%d.%03d %s\n' $(((end_ns - start_ns) / 1000000000)) $((((end_ns - start_ns) / 1000000) % 1000)) \
  "$object" >> "${NAVTWIN_COMPILE_TIMES:-compile-times.txt}"
exit $status

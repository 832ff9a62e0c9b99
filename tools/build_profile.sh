#!/usr/bin/env bash
# Where the build's time and memory go: a fresh `pip wheel .` of this checkout,
# in a clean copy, with every compiler process timed (wall, CPU) and its peak
# memory recorded, one line per translation unit, slowest last.
#
#   tools/build_profile.sh                 # the whole build, then the table
#   tools/build_profile.sh -ftime-report   # the same, with GCC's pass timings per TU in the log
#
# Needs /usr/bin/time (Debian's `time` package). The copy, the log and the wheel go
# to $BUILD_PROFILE_DIR (default /tmp/spotkin_build_profile). docs/build.md has
# the figures and what they led to.
set -euo pipefail
src="$(cd "$(dirname "$0")/.." && pwd)"
out="${BUILD_PROFILE_DIR:-/tmp/spotkin_build_profile}"
[[ -x /usr/bin/time ]] || { echo "needs /usr/bin/time (apt install time)" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out"
mkdir -p "$out/tree" && (cd "$src" && git ls-files -z --cached --others --exclude-standard | xargs -0 cp --parents -t "$out/tree")
cat > "$out/launch.sh" <<'LAUNCH'
#!/bin/sh
src=$(for a in "$@"; do case "$a" in *.cpp|*.cxx) echo "$a";; esac; done | tail -1)
exec /usr/bin/time -a -o "$SPOTKIN_BUILD_LOG" -f "%e %U %S %M ${src:-other}" "$@"
LAUNCH
chmod +x "$out/launch.sh"
export SPOTKIN_BUILD_LOG="$out/units.txt"  # the precompiled header shows as cmake_pch.hxx.cxx
flags="${1:-}"
python3 -m venv "$out/venv"
start=$(date +%s)
(cd "$out/tree" && "$out/venv/bin/pip" wheel . --no-deps -w "$out/wheel" \
  -Ccmake.define.CMAKE_CXX_COMPILER_LAUNCHER="$out/launch.sh" \
  ${flags:+-Ccmake.define.CMAKE_CXX_FLAGS="$flags"} >"$out/pip.log" 2>&1)
end=$(date +%s)
printf "%8s %8s %8s  %s\n" "wall s" "cpu s" "peak MB" "translation unit"
sort -k1 -n "$out/units.txt" | awk -v root="$out/tree/" '{sub(root, "", $5); printf "%8.1f %8.1f %8d  %s\n", $1, $2 + $3, $4 / 1024, $5; cpu += $2 + $3; if ($4 > peak) peak = $4}
  END {printf "compiler CPU %.0f s, largest process %d MB\n", cpu, peak / 1024}'
echo "pip wheel . took $((end - start)) s (wheel in $out/wheel)"

#!/usr/bin/env bash
# Portability check of the C++ core (docs/portability.md): builds the kernel
# harness (bench/cpp/harness.cpp) with Debian's aarch64 cross GCC and with
# Clang (x86_64 and aarch64), and runs its self-checks (`--check`): the aarch64
# builds statically linked, under qemu-aarch64.
#
#   tools/check_arm64.sh              # from a checkout; builds into build/arm64/
#   tools/check_arm64.sh --bindings   # also compiles cpp/bindings/*.cpp and cpp/src/*.cpp (-c) per compiler
#
# Needs: apt-get install -y g++-aarch64-linux-gnu qemu-user clang, and Eigen from
# the cmeel-eigen wheel of .venv/bin/python or of python3 (or EIGEN_INCLUDE).
# Environment: BUILD_DIR (default build/arm64), CHECK_SAMPLES (default 2000),
# EXTRA_CXXFLAGS (appended to every compile, e.g. -std=gnu++17 as the pip build).
# Exits nonzero when a build or a self-check fails. Not part of .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; }
bindings=0
for arg in "$@"; do
  case "$arg" in
    --bindings) bindings=1 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "check_arm64.sh: unknown argument '$arg'" >&2; usage >&2; exit 2 ;;
  esac
done

build=${BUILD_DIR:-build/arm64}
samples=${CHECK_SAMPLES:-2000}

missing=()
for tool in aarch64-linux-gnu-g++ qemu-aarch64 clang++; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
if ((${#missing[@]})); then
  echo "check_arm64.sh: missing ${missing[*]}; on Debian: apt-get install -y g++-aarch64-linux-gnu qemu-user clang" >&2
  exit 2
fi

# Eigen: the cmeel-eigen wheel, as CMakeLists.txt finds it.
eigen=${EIGEN_INCLUDE:-}
if [[ -z "$eigen" ]]; then
  for python in .venv/bin/python python3 python; do
    command -v "$python" >/dev/null 2>&1 || continue
    prefix=$("$python" -c "import importlib.metadata as m; print(m.distribution('cmeel-eigen').locate_file('cmeel.prefix'))" 2>/dev/null) || continue
    if [[ -f "$prefix/include/eigen3/Eigen/Core" ]]; then
      eigen="$prefix/include/eigen3"
      break
    fi
  done
fi
if [[ -z "$eigen" || ! -f "$eigen/Eigen/Core" ]]; then
  echo "check_arm64.sh: no Eigen: pip install cmeel-eigen (into .venv or python3's site), or set EIGEN_INCLUDE" >&2
  exit 2
fi

mkdir -p "$build"
extra=()
read -r -a extra <<<"${EXTRA_CXXFLAGS:-}"
# The package's definitions and warning flags (CMakeLists.txt), at -O2.
flags=(-std=c++17 -O2 -DEIGEN_DONT_VECTORIZE -Wall -Wextra -fno-math-errno -fno-trapping-math
  -I cpp/include -isystem "$eigen" ${extra[@]+"${extra[@]}"})
echo "Eigen: $eigen"
echo "build directory: $build"

summary=()
failures=0
note() { summary+=("$(printf '%-5s %-46s %s' "$1" "$2" "$3")"); [[ "$1" != FAIL ]] || failures=$((failures + 1)); }

# timed LOG COMMAND...: prints and runs COMMAND, its output into LOG (shown on
# failure, its warnings counted); sets `took` (seconds) and returns its status.
timed() {
  local log=$1 start status
  shift
  echo "+ $*"
  start=$(date +%s.%N)
  status=0
  "$@" >"$log" 2>&1 || status=$?
  took=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  local warnings
  warnings=$(grep -c 'warning:' "$log" || true)
  echo "  ${took} s, exit ${status}, ${warnings} warning(s) (log: $log)"
  if ((status != 0)); then tail -n 40 "$log" | sed 's/^/  | /'; fi
  return "$status"
}

# check NAME CXX...: compiles the harness (-c), links it (-static for aarch64),
# runs --check (under qemu-aarch64 for aarch64).
check() {
  local name=$1 target
  shift
  local cxx=("$@") out="$build/harness_$name"
  target=$("${cxx[@]}" -dumpmachine)
  echo
  echo "== $name: ${cxx[*]} (target $target)"
  local static=() runner=()
  if [[ "$target" == aarch64* ]]; then static=(-static) runner=(qemu-aarch64); fi
  if ! timed "$out.compile.log" "${cxx[@]}" "${flags[@]}" -c bench/cpp/harness.cpp -o "$out.o"; then
    note FAIL "$name compile" "exit status, see $out.compile.log"
    return
  fi
  local harness_took=$took
  # the harness times the module's chain kernels: their unit, with its flag (CMakeLists.txt)
  if ! timed "$out.chain.log" "${cxx[@]}" "${flags[@]}" -ffp-contract=off -c cpp/src/chain_kernels.cpp \
    -o "$out.chain.o"; then
    note FAIL "$name compile" "exit status, see $out.chain.log"
    return
  fi
  note PASS "$name compile" "${harness_took} s + ${took} s (chain kernels)"
  if ! timed "$out.link.log" "${cxx[@]}" ${static[@]+"${static[@]}"} "$out.o" "$out.chain.o" -o "$out"; then
    if [[ "${cxx[0]}" == clang* && "$target" == aarch64* ]]; then  # compile-only is the check then
      note SKIP "$name link + self-checks" "no Clang cross runtime (compiled only)"
    else
      note FAIL "$name link" "see $out.link.log"
    fi
    return
  fi
  echo "+ ${runner[*]+${runner[*]} }$out --check $samples"
  local status=0
  ${runner[@]+"${runner[@]}"} "$out" --check "$samples" | tee "$out.check.log" || status=$?
  local tally
  tally=$(grep -E '^harness self-check: ' "$out.check.log" | tail -n 1 | sed 's/^harness self-check: //') || true
  if ((status == 0)); then
    note PASS "$name self-checks" "${tally:-?}"
  else
    note FAIL "$name self-checks" "${tally:-no result} (exit $status)"
  fi
}

check gcc-aarch64 aarch64-linux-gnu-g++
check clang-x86_64 clang++
check clang-aarch64 clang++ --target=aarch64-linux-gnu

# Every header of the core in one translation unit, for each compiler (syntax only: the
# harness above and --bindings instantiate the templates).
echo
echo "== headers: every cpp/include/spotkin/**/*.hpp in one translation unit (each twice)"
headers=$(cd cpp/include && find spotkin -name '*.hpp' | LC_ALL=C sort)
for name_cxx in "gcc-aarch64:aarch64-linux-gnu-g++" "clang-x86_64:clang++" "clang-aarch64:clang++ --target=aarch64-linux-gnu"; do
  name=${name_cxx%%:*}
  read -r -a cxx <<<"${name_cxx#*:}"
  tu="$build/headers_$name.cpp"
  : >"$tu"
  for h in $headers; do printf '#include "%s"\n#include "%s"\n' "$h" "$h" >>"$tu"; done  # twice: include guards
  if timed "$build/headers_$name.log" "${cxx[@]}" "${flags[@]}" -fsyntax-only "$tu"; then
    note PASS "$name headers" "$(wc -l <<<"$headers") headers, ${took} s"
  else
    note FAIL "$name headers" "see $build/headers_$name.log"
  fi
done

if ((bindings)); then
  # The Python module's sources, compile-only (this Python's and pybind11's headers; no link).
  python=$(command -v .venv/bin/python || command -v python3)
  if py_includes=$("$python" -c "import sysconfig, pybind11; print(sysconfig.get_paths()['include']); print(pybind11.get_include())" 2>/dev/null); then
    mapfile -t py_includes <<<"$py_includes"
    for name_cxx in "gcc-aarch64:aarch64-linux-gnu-g++" "clang-x86_64:clang++" "clang-aarch64:clang++ --target=aarch64-linux-gnu"; do
      name=${name_cxx%%:*}
      read -r -a cxx <<<"${name_cxx#*:}"
      echo
      echo "== bindings: ${cxx[*]} -c cpp/bindings/*.cpp cpp/src/*.cpp"
      mkdir -p "$build/bindings_$name"
      for src in cpp/bindings/*.cpp cpp/src/*.cpp; do
        base=$(basename "$(dirname "$src")")_$(basename "$src" .cpp)
        if timed "$build/bindings_$name/$base.log" "${cxx[@]}" "${flags[@]}" -fPIC -isystem "${py_includes[0]}" \
          -isystem "${py_includes[1]}" -c "$src" -o "$build/bindings_$name/$base.o"; then
          note PASS "$name ${src#cpp/}" "${took} s"
        else
          note FAIL "$name ${src#cpp/}" "see $build/bindings_$name/$base.log"
        fi
      done
    done
  else
    note FAIL "bindings" "no pybind11 for $python (pip install pybind11)"
  fi
fi

echo
echo "== summary"
printf '%s\n' "${summary[@]}"
if ((failures)); then
  echo "check_arm64.sh: $failures step(s) failed"
  exit 1
fi
echo "check_arm64.sh: all steps passed"

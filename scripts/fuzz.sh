#!/usr/bin/env bash
# Builds the fuzz targets (fuzz/) with clang, libFuzzer, ASan and UBSan in
# build-fuzz/ and runs each for SECONDS (default 60) on the seed corpus: every
# shipped netlist and bad netlist (netlist reader), every catalogue (catalogue
# reader). Exit status non-zero when a target crashes or a sanitizer reports.
#   scripts/fuzz.sh [SECONDS] [TARGET...]     TARGET: netlist, catalogue (default both)
# New inputs found go to build-fuzz/corpus/TARGET (kept between runs), crash
# reproducers to build-fuzz/artifacts/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
targets=("$@")
if [ "${#targets[@]}" -eq 0 ]; then targets=(netlist catalogue); fi
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g"
cmake -S . -B build-fuzz -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
  -DPNEUMO_FUZZ=ON -DPNEUMO_BUILD_TESTS=OFF -DPNEUMO_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-fuzz -j2 --target "${targets[@]/%/_fuzzer}"
mkdir -p build-fuzz/artifacts
export ASAN_OPTIONS="detect_leaks=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
for t in "${targets[@]}"; do
  case "$t" in
    netlist) seeds=(netlists tests/data/bad_netlists) ;;
    catalogue) seeds=(catalogues) ;;
    *) echo "fuzz: unknown target '$t' (netlist, catalogue)" >&2; exit 2 ;;
  esac
  mkdir -p "build-fuzz/corpus/$t"
  echo "fuzz: $t for ${seconds} s"
  # A target that runs out of memory makes libFuzzer print a heap profile,
  # which over millions of allocations can take longer than the run itself:
  # the time limit keeps a finding from holding CI until its own limit.
  if ! timeout --signal=KILL "$((seconds + 300))" "build-fuzz/fuzz/${t}_fuzzer" -max_total_time="$seconds" \
      -print_final_stats=1 -max_len=8192 -artifact_prefix=build-fuzz/artifacts/ "build-fuzz/corpus/$t" "${seeds[@]}"; then
    echo "fuzz: $t failed (a crash, a sanitizer report, out of memory, or killed after $((seconds + 300)) s)" >&2
    exit 1
  fi
done

#!/usr/bin/env bash
# Fuzzes dispel's readers of outside data with libFuzzer, ASan and UBSan (docs/fuzzing.md):
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
# configures and builds build-fuzz/ with clang (only the fuzz targets and the libraries they
# link), then runs each TARGET (default: every one of tests/fuzz/targets.txt) for SECONDS
# (default 30) on a fresh copy of its seed corpus (tests/fuzz/corpus/<target>/ and the shipped
# files targets.txt names), in build-fuzz/corpus/<target>/. Prints one line per target (runs,
# result); a crash, leak, timeout (10 s) or out-of-memory (4 GiB) leaves its input in
# build-fuzz/artifacts/<target>/, is printed with its path, and makes the script exit 1.
# tests/fuzz/<target>.dict, when there is one, is the target's libFuzzer dictionary.
# Replay one: build-fuzz/tests/fuzz/fuzz_<target> <input>.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
[ $# -gt 0 ] && shift
case "$seconds" in
  '' | *[!0-9]*) echo "usage: $0 [SECONDS] [TARGET...]" >&2; exit 2 ;;
esac

declare -A max_len seeds
all=()
while read -r name len paths; do
  case "$name" in '' | '#'*) continue ;; esac
  all+=("$name")
  max_len[$name]=$len
  seeds[$name]=$paths
done < tests/fuzz/targets.txt
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
for t in "${targets[@]}"; do
  [ -n "${max_len[$t]:-}" ] || { echo "fuzz: unknown target $t (${all[*]})" >&2; exit 2; }
done

build=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DDISPEL_FUZZ=ON -DDISPEL_BUILD_TESTS=OFF \
  -DDISPEL_BUILD_APPS=OFF -DDISPEL_BUILD_BENCHMARKS=OFF -DDISPEL_WITH_MRPT_RAWLOG=OFF \
  -DDISPEL_WITH_ROS1=OFF >/dev/null
build_targets=()
for t in "${targets[@]}"; do build_targets+=(--target "fuzz_$t"); done
cmake --build "$build" -j"$(nproc)" "${build_targets[@]}"

failed=0
summary=()
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t
  artifacts=$build/artifacts/$t
  log=$build/fuzz_$t.log
  rm -rf "$corpus" "$artifacts"
  mkdir -p "$corpus" "$artifacts"
  [ -d "tests/fuzz/corpus/$t" ] && find "tests/fuzz/corpus/$t" -maxdepth 1 -type f -exec cp {} "$corpus"/ \;
  for p in ${seeds[$t]}; do
    find "$p" -maxdepth 1 -type f ! -name LICENSE -exec cp {} "$corpus"/ \;
  done
  echo "fuzz: $t for $seconds s on $(find "$corpus" -type f | wc -l) seeds (log: $log)"
  dict=()
  [ -f "tests/fuzz/$t.dict" ] && dict=(-dict="tests/fuzz/$t.dict")
  rc=0
  # Leaks are checked (ASan's default); -error_exitcode is libFuzzer's for any finding.
  ASAN_OPTIONS=abort_on_error=0:detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -max_len="${max_len[$t]}" -artifact_prefix="$artifacts/" -print_final_stats=1 \
    "${dict[@]}" "$corpus" >"$log" 2>&1 || rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  [ -n "$runs" ] || runs=$(grep -o '#[0-9]*' "$log" | tail -1 | tr -d '#')
  found=$(find "$artifacts" -type f | head -1)
  if [ $rc -ne 0 ] || [ -n "$found" ]; then
    failed=1
    kind=$(grep -m1 -oE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer|UndefinedBehaviorSanitizer)[^(]*|runtime error: .*|fuzz: the error .{0,80}' "$log" || true)
    summary+=("$t: FAILED after ${runs:-?} runs (exit $rc): ${kind:-see $log}; input: ${found:-none}")
    tail -n 40 "$log" >&2
  else
    summary+=("$t: ok, ${runs:-?} runs in $seconds s, corpus $(find "$corpus" -type f | wc -l) inputs")
  fi
done
printf 'fuzz: %s\n' "${summary[@]}"
exit $failed

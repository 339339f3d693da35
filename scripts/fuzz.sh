#!/usr/bin/env bash
# Fuzzes dispel's readers of outside data with libFuzzer, ASan and UBSan (docs/fuzzing.md):
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
# configures and builds build-fuzz/ with clang (only the fuzz targets and the libraries they
# link), then runs each TARGET (default: every one of tests/fuzz/targets.txt) for SECONDS
# (default 30), FUZZ_JOBS targets at a time (default: one per core), on a fresh copy of its seed
# corpus (tests/fuzz/corpus/<target>/ and the shipped files targets.txt names), in
# build-fuzz/corpus/<target>/. Prints one line per target (runs, result); a crash, leak,
# timeout (10 s) or out-of-memory (4 GiB) leaves its input in build-fuzz/artifacts/<target>/, is
# printed with its path, and makes the script exit 1.
# tests/fuzz/<target>.dict, when there is one, is the target's libFuzzer dictionary;
# tests/fuzz/<target>.options, when there is one, adds libFuzzer options (a line of words, # for
# comments): mrpt_rawlog runs in fork mode, its out-of-memory and timeout inputs and the crashes
# that are ASan's failed `new` (MRPT's own allocations, docs/fuzzing.md) kept in its artifacts
# and counted but not failed.
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
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DDISPEL_FUZZ=ON -DDISPEL_BUILD_TESTS=OFF \
  -DDISPEL_BUILD_APPS=OFF -DDISPEL_BUILD_BENCHMARKS=OFF -DDISPEL_WITH_MRPT_RAWLOG=ON \
  -DDISPEL_WITH_ROS1=OFF >/dev/null
build_targets=()
for t in "${targets[@]}"; do build_targets+=(--target "fuzz_$t"); done
cmake --build "$build" -j"$(nproc)" "${build_targets[@]}"

# How long past its -max_total_time a run may go before it is a hang: libFuzzer's wrap-up (the
# final merge of fork mode, a last input of up to -timeout=10 s) takes seconds; 120 s more covers
# a machine busy with the other target and CI's other work.
overrun_limit=${FUZZ_OVERRUN_LIMIT:-120}

# watchdog PID SECONDS REPORT: after SECONDS, if the process group PID (setsid) still runs,
# writes the stacks of its processes to REPORT and kills the group.
watchdog() {
  local pid=$1 limit=$2 report=$3 p
  sleep "$limit"
  kill -0 "$pid" 2>/dev/null || return 0
  {
    echo "fuzz.sh: still running ${limit} s after it started; the stacks of process group $pid:"
    for p in $(pgrep -g "$pid"); do
      echo "--- process $p: $(tr '\0' ' ' </proc/"$p"/cmdline 2>/dev/null | cut -c1-200)"
      if command -v gdb >/dev/null; then
        timeout 60 gdb -p "$p" -batch -nx -ex 'thread apply all bt 30' 2>&1 | grep -E '^(#|Thread)' || true
      fi
    done
  } >"$report.partial" 2>&1
  mv "$report.partial" "$report"
  kill -KILL -- -"$pid" 2>/dev/null || true
}

# One target's run; its summary line goes to build-fuzz/result_<target> ("<target>: ok, ..." or
# "<target>: FAILED ...").
fuzz_one() {
  local t=$1
  local corpus artifacts log dict options ignored_kinds ignore_crashes limits rc runs replay
  local ignored not_ignored found kind n c k o
  local result=$build/result_$t
  rm -f "$result"
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
  options=()
  if [ -f "tests/fuzz/$t.options" ]; then
    read -r -a options < <(sed 's/#.*//' "tests/fuzz/$t.options" | tr '\n' ' ') || true
  fi
  ignored_kinds=()
  ignore_crashes=0
  limits=(-rss_limit_mb=4096)
  for o in "${options[@]}"; do
    case "$o" in
      -ignore_ooms=1) ignored_kinds+=(oom) ;;
      # A slow unit (libFuzzer's slow-unit-*: an input that took longer than -report_slow_units,
      # 10 s, without a timeout being called) is a timeout's kind: ignored with timeouts.
      -ignore_timeouts=1) ignored_kinds+=(timeout slow-unit) ;;
      -ignore_crashes=1) ignore_crashes=1 ;;
      -malloc_limit_mb=*) limits+=("$o") ;;
    esac
  done
  rc=0
  # Leaks are checked (ASan's default); -error_exitcode is libFuzzer's for any finding. A malloc
  # (aligned_alloc, ...) the allocator cannot serve returns null, as it does outside ASan, so
  # that what the code does with that null is seen (MRPT's matrices wrote through it); a `new` it
  # cannot serve still aborts (ASan's), where outside ASan it throws std::bad_alloc. One above
  # 4 GiB that it can serve is libFuzzer's out-of-memory (-rss_limit_mb).
  # The fuzzer runs in its own process group (setsid), fork mode's children with it, under a
  # watchdog: libFuzzer ends a run at -max_total_time only between inputs, and waits for fork
  # mode's jobs, so a run that hangs where its own timeout does not fire would hold CI until CI's
  # own limit (stop 40's run did: no result line after 90 minutes). One still going
  # $overrun_limit s after its time is stopped: the stacks of its processes go to
  # build-fuzz/hang_<target>.txt (gdb), the group is killed, and the target fails, naming the hang.
  ASAN_OPTIONS=abort_on_error=0:detect_leaks=1:allocator_may_return_null=1 \
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    setsid "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -max_len="${max_len[$t]}" -artifact_prefix="$artifacts/" -print_final_stats=1 \
    "${dict[@]}" "${options[@]}" "$corpus" >"$log" 2>&1 &
  local fuzzer=$!
  local hang=$build/hang_$t.txt
  rm -f "$hang"
  watchdog "$fuzzer" $((seconds + overrun_limit)) "$hang" >/dev/null 2>&1 </dev/null &
  local dog=$!
  wait "$fuzzer" || rc=$?
  pkill -P "$dog" 2>/dev/null || true
  kill "$dog" 2>/dev/null || true
  wait "$dog" 2>/dev/null || true
  if [ -f "$hang" ]; then
    runs=$(grep -oE '^#[0-9]+' "$log" | tail -1 | tr -d '#' || true)
    echo "$t: FAILED after ${runs:-?} runs: still running $((seconds + overrun_limit)) s after it started, its time $seconds s (a hang; the stacks of its processes: $hang)" >"$result"
    tail -n 20 "$log" >&2
    cat "$hang" >&2
    return
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  [ -n "$runs" ] || runs=$(grep -oE '^#[0-9]+' "$log" | tail -1 | tr -d '#' || true)
  # With -ignore_crashes=1 the run goes on after a crash, but only one kind of crash is ignored:
  # an allocation ASan's allocator cannot make (it aborts where the process would get
  # std::bad_alloc). Each crash input is replayed; one of that kind is renamed oom-asan-*, any
  # other stays a crash and fails the run.
  if [ $ignore_crashes -eq 1 ]; then
    for c in $(find "$artifacts" -type f -name 'crash-*'); do
      replay=$(ASAN_OPTIONS=abort_on_error=0:detect_leaks=1:allocator_may_return_null=1 \
        UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 timeout 120 \
        "$build/tests/fuzz/fuzz_$t" "${limits[@]}" "$c" 2>&1 || true)
      if grep -qE 'SUMMARY: AddressSanitizer: (out-of-memory|allocation-size-too-big)' <<<"$replay"; then
        mv "$c" "$artifacts/oom-asan-${c##*/crash-}"
      fi
    done
  fi
  ignored=""
  not_ignored=()
  for k in "${ignored_kinds[@]}"; do
    n=$(find "$artifacts" -type f -name "$k-*" | wc -l)
    [ "$n" -eq 0 ] || ignored+=", $n $k inputs ignored (docs/fuzzing.md) in $artifacts"
    not_ignored+=(! -name "$k-*")
  done
  found=$(find "$artifacts" -type f "${not_ignored[@]}" | head -1)
  # In fork mode libFuzzer exits with the code of its last failed job, an ignored one too: the
  # run failed when it left an input that is not ignored, or failed and left none.
  [ -n "$ignored" ] && [ -z "$found" ] && rc=0
  if [ $rc -ne 0 ] || [ -n "$found" ]; then
    kind=$(grep -m1 -oE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer|UndefinedBehaviorSanitizer)[^(]*|runtime error: .*|fuzz: the error .{0,80}' "$log" || true)
    echo "$t: FAILED after ${runs:-?} runs (exit $rc): ${kind:-see $log}; input: ${found:-none}" >"$result"
    tail -n 40 "$log" >&2
  else
    echo "$t: ok, ${runs:-?} runs in $seconds s, corpus $(find "$corpus" -type f | wc -l) inputs$ignored" >"$result"
  fi
}

# The targets run FUZZ_JOBS at a time (default: one per core; each is one process, mrpt_rawlog's
# fork mode one child), each for the whole SECONDS.
max_jobs=${FUZZ_JOBS:-$(nproc)}
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$max_jobs" ]; do wait -n || true; done
  fuzz_one "$t" &
done
wait
failed=0
for t in "${targets[@]}"; do
  if [ -f "$build/result_$t" ]; then
    echo "fuzz: $(cat "$build/result_$t")"
    grep -q "^$t: ok" "$build/result_$t" || failed=1
  else
    echo "fuzz: $t: FAILED: the run ended without a result (see $build/fuzz_$t.log)"
    failed=1
  fi
done
exit $failed

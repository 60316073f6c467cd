#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz/CMakeLists.txt, clang) and fuzzes each for a while,
# starting from seeds made by keygrid's own writers plus the regression corpus
# (tests/fuzz/corpus/<target>/: inputs that once crashed, kept so they are replayed).
#
#   bash tests/fuzz/run.sh [--seconds N] [--build DIR] [--targets "rawlog tum ini png"]
#
# Prints per target the executions, exec/s and coverage (libFuzzer's cov / ft); exits 1 when a
# target crashes, leaks, hangs (-timeout) or trips a sanitizer, naming the input that did it.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
src="$(cd "$here/../.." && pwd)"
seconds=60
build="$src/build-fuzz"
targets="rawlog tum ini png"
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --targets) targets="$2"; shift 2 ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
command -v clang++ >/dev/null || { echo "run.sh: clang++ missing (Debian: clang, libclang-rt-14-dev)" >&2; exit 2; }

CXX=clang++ cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j2 >/dev/null
seeds="$build/seeds"
rm -rf "$seeds"
ASAN_OPTIONS=detect_leaks=0 "$build/keygrid_fuzz_make_seeds" "$seeds" "$src"

status=0
# Fork mode (-fork=1): inputs run in child processes, and an input that needs more memory than
# -rss_limit_mb / -malloc_limit_mb is counted (oom) but does not stop the run. Such inputs are
# damaged lengths inside MRPT objects (a string, a vector) that MRPT allocates before it reads
# them; outside the sanitizer the allocation throws std::bad_alloc (reported as a corrupt
# input) or succeeds for the moment it takes to hit the end of the file. Crashes, sanitizer
# reports and timeouts still stop the run and fail it.
# allocator_may_return_null: malloc returns null as it does when the system refuses the memory
# (OpenCV then throws); code that writes through such a null pointer still crashes the run.
export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
for t in $targets; do
  work="$build/work/$t"
  artifacts="$build/artifacts/$t"  # kept across runs: crashes to add to corpus/$t
  rm -rf "$work"; mkdir -p "$work/corpus" "$artifacts"
  cp -r "$seeds/$t/." "$work/corpus/"
  [ -d "$here/corpus/$t" ] && cp -r "$here/corpus/$t/." "$work/corpus/"
  log="$work/fuzz.log"
  t0=$(date +%s)
  # A guard against a run that does not end: SIGINT 60 s after the time (libFuzzer then exits
  # as at the end of the time), SIGKILL 20 s after that.
  (cd "$work" && timeout -s INT -k 20 "$((seconds + 60))" "$build/fuzz_$t" -max_total_time="$seconds" -fork=1 -ignore_ooms=1 -ignore_timeouts=0 -ignore_crashes=0 -timeout=20 -rss_limit_mb=2560 -seed=1 \
        -max_len=1048576 -artifact_prefix="$artifacts/" -print_final_stats=1 corpus >"$log" 2>&1) || true
  # Fork mode: the parent's progress lines "#N: cov: C ft: F ... exec/s S oom/timeout/crash: O/T/X".
  # The parent exits non-zero after OOM inputs too, so the verdict is read from the log: any
  # crash, timeout or leak input written, or counted, fails the target.
  last=$(grep -E '^#[0-9]+: cov:' "$log" | tail -1 || true)
  runs=$(echo "$last" | grep -oE '^#[0-9]+' | tr -d '#' || true)
  cov=$(echo "$last" | grep -oE 'cov: [0-9]+ ft: [0-9]+' || true)
  triple=$(echo "$last" | grep -oE 'oom/timeout/crash: [0-9]+/[0-9]+/[0-9]+' | grep -oE '[0-9]+/[0-9]+/[0-9]+' || echo "0/0/0")
  ooms=${triple%%/*}; rest=${triple#*/}; timeouts=${rest%%/*}; crashes=${rest#*/}
  if grep -qE 'Test unit written to .*/(crash|timeout|leak)-' "$log" || [ "${timeouts:-0}" != 0 ] || [ "${crashes:-0}" != 0 ] || [ -z "$last" ]; then
    result=FAILED; status=1
  else
    result=ok
  fi
  elapsed=$(( $(date +%s) - t0 ))
  speed=$(( ${runs:-0} / (elapsed > 0 ? elapsed : 1) ))
  printf 'fuzz_%-7s %-6s %10s execs  %7s exec/s  %s  oom inputs %s  (%s s)\n' "$t" "$result" "${runs:-?}" "$speed" "$cov" "${ooms:-0}" "$elapsed"
  if [ "$result" = FAILED ]; then
    grep -E 'ERROR|SUMMARY|Test unit written' "$log" | head -5
    echo "  log: $log"
  fi
done
exit $status

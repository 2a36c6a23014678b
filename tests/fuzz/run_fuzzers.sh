#!/usr/bin/env bash
# Build the libFuzzer targets (clang, ASan + UBSan) and run each for a while, seeded from
# tests/data, tests/fuzz/seeds and the regression files in tests/data/fuzz. Crashes, leaks,
# timeouts and out-of-memory inputs are saved under $OUT/artifacts/fuzz_<target>-*; the
# script exits 1 if there is any. A summary table (the one in tests/fuzz/README.md) is
# printed at the end and written to $OUT/summary.md.
#   usage: tests/fuzz/run_fuzzers.sh [SECONDS_PER_TARGET (default 60)] [TARGET...]
#   env:   BUILD_DIR (default /tmp/nonbloppy-fuzz-build), OUT (default /tmp/nonbloppy-fuzz),
#          JOBS (make -j, default 1), PARALLEL (targets fuzzed at once, default 1)
# Reproduce one artifact:  $BUILD_DIR/tests/fuzz/fuzz_vtu $OUT/artifacts/fuzz_vtu-crash-...
# Every target runs with the same limits: 10 s per input is a hang, and more than 2048 MB
# of RSS or a single malloc above 2048 MB is out-of-memory (libFuzzer's -malloc_limit_mb
# defaults to -rss_limit_mb).
# fuzz_vdb_points, explicitly: libopenvdb's tree and point-attribute readers allocate what
# sizes inside a grid's tree say, which src/ReadVdbPoints.cc cannot check without
# reimplementing that I/O (tests/fuzz/README.md). So that target runs in libFuzzer's fork
# mode, which goes on after a crash or OOM, and every artifact is then sorted by its
# allocation stack: allocated inside libopenvdb.so -> "upstream" (listed, kept, does not fail
# the run); anything else (our code, a leak, UB, a hang, RSS growth) -> FAILED.
# VDB_STRICT=1 runs it like the others (stops at, and fails on, the first finding).
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-60}"
shift || true
targets=("$@")
((${#targets[@]})) || targets=(bgeo vtu table json vdb_points vtk ply vtk_file ply_file bgeo_file table_file json_file obj_file)
build_dir="${BUILD_DIR:-/tmp/nonbloppy-fuzz-build}"
out="${OUT:-/tmp/nonbloppy-fuzz}"
parallel="${PARALLEL:-1}"

command -v clang++ >/dev/null || { echo "run_fuzzers: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DNONBLOPPY_BUILD_FUZZERS=ON -DNONBLOPPY_BUILD_TOOLS=OFF -DNONBLOPPY_BUILD_TESTS=OFF >/dev/null
cmake --build "$build_dir" -j"${JOBS:-1}" --target $(printf 'fuzz_%s ' "${targets[@]}") -- --no-print-directory

# Seeds per target: the data files it reads, the hand-made seeds, and the regression files.
seeds_for() {
  case "$1" in
    bgeo|bgeo_file) echo "tests/data/*.bgeo tests/fuzz/seeds/*.bgeo tests/data/fuzz/*.bgeo" ;;
    vtu) echo "tests/data/*.vtu tests/fuzz/seeds/*.vtu tests/data/fuzz/*.vtu" ;;
    table|table_file) echo "tests/fuzz/seeds/*.csv tests/fuzz/seeds/*.txt tests/data/fuzz/*.csv tests/data/fuzz/*.txt" ;;
    json|json_file) echo "tests/fuzz/seeds/*.json tests/data/fuzz/*.json" ;;
    vdb_points) echo "tests/fuzz/seeds/*.vdb tests/data/fuzz/*.vdb" ;;
    vtk|vtk_file) echo "tests/data/cube_8_particles.vtk tests/data/free_particles_125_particles.vtk tests/data/fuzz/*.vtk" ;;
    ply|ply_file) echo "tests/fuzz/seeds/*.ply tests/data/fuzz/*.ply" ;;
    obj_file) echo "tests/fuzz/seeds/*.obj tests/data/fuzz/*.obj" ;;
    *) echo "run_fuzzers: unknown target '$1'" >&2; exit 2 ;;
  esac
}

# True if the sanitizer or libFuzzer report for artifact $2 of target $1 is an allocation
# made inside libopenvdb.so: the first frame of its stack that is in libopenvdb or in our
# src/ is in libopenvdb.
allocated_in_openvdb() {
  local report
  report=$("$build_dir/tests/fuzz/fuzz_$1" "$2" -rss_limit_mb=2048 -timeout=10 2>&1 || true)
  grep -qE "allocation-size-too-big|out-of-memory \(malloc|out-of-memory \(requested|allocator is out of memory" <<<"$report" || return 1
  sed -n '/ERROR: /,$p' <<<"$report" | grep -m1 -E "libopenvdb\.so|/src/[A-Za-z]+\.cc" | grep -q libopenvdb
}

# Run one target; its result line goes to $out/result_<target>.
fuzz_one() {
  local t="$1" corpus="$out/corpus/$1" log="$out/fuzz_$1.log" result=clean f
  mkdir -p "$corpus"
  for f in $(seeds_for "$t"); do [ -f "$f" ] && cp -n "$f" "$corpus/" || true; done
  touch "$out/start_$t"
  echo "run_fuzzers: fuzz_$t for ${seconds}s ($(ls "$corpus" | wc -l) corpus files)"
  # lsan.supp: LeakSanitizer suppressions, none at the moment (src/ReadVdbPoints.cc rejects the
  # corrupt chunks on which libopenvdb threw and leaked), so every leak counts.
  local fork=()
  [ "$t" = vdb_points ] && [ "${VDB_STRICT:-0}" != 1 ] && fork=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=0)
  local start=$SECONDS
  export ASAN_OPTIONS="detect_leaks=1" LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp" \
         UBSAN_OPTIONS="print_stacktrace=1"
  "$build_dir/tests/fuzz/fuzz_$t" "$corpus" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 "${fork[@]}" \
    -artifact_prefix="$out/artifacts/fuzz_$t-" >"$log" 2>&1 || result="FAILED:"
  local elapsed=$((SECONDS - start)) artifact upstream="" ours=""
  for artifact in $(find "$out/artifacts" -name "fuzz_$t-*" -newer "$out/start_$t" | sort); do
    if ((${#fork[@]})) && allocated_in_openvdb "$t" "$artifact"; then
      upstream+=" $(basename "$artifact")"
    else
      ours+=" $(basename "$artifact")"
    fi
  done
  if [ -n "$ours" ] || [ "$result" != clean -a -z "$upstream" ]; then
    result="FAILED:${ours:- (see $log)}"
  elif [ -n "$upstream" ]; then
    result="clean except $(wc -w <<<"$upstream") upstream allocation(s) in libopenvdb:$upstream"
  fi
  local execs peak
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  # Fork mode prints no final stats; its progress lines are "#<execs>: cov: ...".
  [ -n "$execs" ] || execs=$(sed -n 's/^#\([0-9]*\): cov:.*/\1/p' "$log" | tail -1)
  peak=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
  local runs_in=$elapsed
  printf '| fuzz_%s | %s | %s | %s | %s | %s |\n' "$t" "${runs_in:-?}" "${execs:-?}" \
    "$(ls "$corpus" | wc -l)" "${peak:-n/a}" "$result" >"$out/result_$t"
  echo "run_fuzzers: fuzz_$t: $result (log $log)"
}

mkdir -p "$out/artifacts"
rm -f "$out"/result_*
running=0
for t in "${targets[@]}"; do
  if ((parallel > 1)); then
    fuzz_one "$t" &
    running=$((running + 1))
    if ((running >= parallel)); then wait -n || true; running=$((running - 1)); fi
  else
    fuzz_one "$t"
  fi
done
wait

{
  echo "| target | seconds | executions | corpus files | peak RSS (MB) | result |"
  echo "|---|---|---|---|---|---|"
  for t in "${targets[@]}"; do cat "$out/result_$t"; done
} >"$out/summary.md"
cat "$out/summary.md"
! grep -q FAILED "$out/summary.md"

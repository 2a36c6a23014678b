#!/usr/bin/env bash
# Build the libFuzzer targets (clang, ASan + UBSan) and run each for a while, seeded from
# tests/data and tests/fuzz/seeds. Crashes, leaks and timeouts are saved under
# $OUT/artifacts/<target>-*; the script exits 1 if there is any.
#   usage: tests/fuzz/run_fuzzers.sh [SECONDS_PER_TARGET (default 60)] [TARGET...]
#   env:   BUILD_DIR (default /tmp/nonbloppy-fuzz-build), OUT (default /tmp/nonbloppy-fuzz),
#          JOBS (make -j, default 1)
# Reproduce one artifact:  $BUILD_DIR/tests/fuzz/fuzz_vtu $OUT/artifacts/fuzz_vtu-crash-...
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-60}"
shift || true
targets=("$@")
((${#targets[@]})) || targets=(bgeo vtu table json vdb_points vtk ply)
build_dir="${BUILD_DIR:-/tmp/nonbloppy-fuzz-build}"
out="${OUT:-/tmp/nonbloppy-fuzz}"

command -v clang++ >/dev/null || { echo "run_fuzzers: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DNONBLOPPY_BUILD_FUZZERS=ON -DNONBLOPPY_BUILD_TOOLS=OFF -DNONBLOPPY_BUILD_TESTS=OFF >/dev/null
cmake --build "$build_dir" -j"${JOBS:-1}" --target $(printf 'fuzz_%s ' "${targets[@]}") -- --no-print-directory

# Seeds per target: the data files it reads, the hand-made seeds, and the regression files.
seeds_for() {
  case "$1" in
    bgeo) echo "tests/data/*.bgeo tests/fuzz/seeds/*.bgeo tests/data/fuzz/*.bgeo" ;;
    vtu) echo "tests/data/*.vtu tests/fuzz/seeds/*.vtu tests/data/fuzz/*.vtu" ;;
    table) echo "tests/fuzz/seeds/*.csv tests/fuzz/seeds/*.txt tests/data/fuzz/*.csv tests/data/fuzz/*.txt" ;;
    json) echo "tests/fuzz/seeds/*.json tests/data/fuzz/*.json" ;;
    vdb_points) echo "tests/fuzz/seeds/*.vdb tests/data/fuzz/*.vdb" ;;
    vtk) echo "tests/data/cube_8_particles.vtk tests/data/free_particles_125_particles.vtk tests/data/fuzz/*.vtk" ;;
    ply) echo "tests/fuzz/seeds/*.ply tests/data/fuzz/*.ply" ;;
  esac
}

mkdir -p "$out/artifacts"
status=0
for t in "${targets[@]}"; do
  corpus="$out/corpus/$t"
  mkdir -p "$corpus"
  for f in $(seeds_for "$t"); do [ -f "$f" ] && cp -n "$f" "$corpus/" || true; done
  echo "run_fuzzers: fuzz_$t for ${seconds}s ($(ls "$corpus" | wc -l) corpus files)"
  # libopenvdb (not instrumented) leaks a node when it throws on a corrupt stream; that is
  # upstream's, so leak checking is off for the VDB target only.
  leaks=1
  [ "$t" = vdb_points ] && leaks=0
  # 10 s per input is a hang; 2 GB is more than any valid small input needs.
  if ! ASAN_OPTIONS="detect_leaks=$leaks" "$build_dir/tests/fuzz/fuzz_$t" "$corpus" -max_total_time="$seconds" -timeout=10 \
       -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
       -artifact_prefix="$out/artifacts/fuzz_$t-" >"$out/fuzz_$t.log" 2>&1; then
    echo "run_fuzzers: fuzz_$t FAILED; see $out/fuzz_$t.log and $out/artifacts/" >&2
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^#[0-9]+ *DONE" "$out/fuzz_$t.log" | tail -2 || true
done
exit $status

#!/usr/bin/env bash
# ctest benchmark_scripts: the parts of the benchmark's summary that can be checked without
# running it. tests/bench/update_readme.sh replaces exactly the lines between the README's
# benchmark markers, refuses a README without them (one line, exit 2, the file untouched),
# and the repository's README.md holds the markers it needs; tests/bench/targets_table.sh
# says met or missed right at each target's edge.
#   usage: test_bench_scripts.sh SOURCE_DIR
set -euo pipefail
source_dir="$1"
script="$source_dir/tests/bench/update_readme.sh"
source "$(dirname "$0")/check.sh"  # $work, check, finish

begin='<!-- benchmark summary: begin -->'
end='<!-- benchmark summary: end -->'
printf '# title\n%s\nold table\nold targets\n%s\ntail\n' "$begin" "$end" > "$work/README.md"
chmod 640 "$work/README.md"
printf '**Latest run**: new\n\n| a | b |\n' > "$work/summary.md"

# The block is replaced, the lines around it kept, the file's mode kept, no file left over.
bash "$script" "$work/summary.md" "$work/README.md" 2> "$work/err"
check "spliced README" "$(printf '# title\n%s\n**Latest run**: new\n\n| a | b |\n%s\ntail' "$begin" "$end")" "$(cat "$work/README.md")"
check "mode kept" "640" "$(stat -c %a "$work/README.md")"
check "nothing left beside it" "README.md err summary.md" "$(ls "$work" | tr '\n' ' ' | sed 's/ $//')"
# Twice gives the same file.
cp "$work/README.md" "$work/once.md"
bash "$script" "$work/summary.md" "$work/README.md" 2> /dev/null
check "idempotent" "$(cat "$work/once.md")" "$(cat "$work/README.md")"
rm "$work/once.md"

# refused SUMMARY README EXPECTED_MESSAGE: exit 2, that one line, the README as it was.
refused() {
  cp "$2" "$work/before"
  local status=0
  bash "$script" "$1" "$2" 2> "$work/err" || status=$?
  check "exit status for: $3" 2 "$status"
  check "message" "$3" "$(cat "$work/err")"
  check "README untouched for: $3" "$(cat "$work/before")" "$(cat "$2")"
}
printf '# no markers\n' > "$work/plain.md"
refused "$work/summary.md" "$work/plain.md" \
  "update_readme.sh: $work/plain.md must hold the line '$begin' once and the line '$end' once after it (found 0 and 0)"
printf '%s\n%s\nx\n%s\n' "$begin" "$end" "$begin" > "$work/twice.md"
refused "$work/summary.md" "$work/twice.md" \
  "update_readme.sh: $work/twice.md must hold the line '$begin' once and the line '$end' once after it (found 2 and 1)"
printf '%s\nx\n%s\n' "$end" "$begin" > "$work/reversed.md"
refused "$work/summary.md" "$work/reversed.md" "update_readme.sh: $work/reversed.md has '$end' before '$begin'"
refused "$work/missing.md" "$work/README.md" "update_readme.sh: cannot read the summary $work/missing.md"
: > "$work/empty.md"
refused "$work/empty.md" "$work/README.md" "update_readme.sh: the summary $work/empty.md is empty"

# The repository's README can take a run's summary: each marker once, in order, and what
# lies between them is a summary as run_benchmark.sh writes it (the latest run's line, the
# main table, the targets table).
check "README markers" "1 1" "$(grep -cxF -- "$begin" "$source_dir/README.md") $(grep -cxF -- "$end" "$source_dir/README.md")"
block=$(sed -n "\\|^$begin\$|,\\|^$end\$|p" "$source_dir/README.md")
check "README block starts with the latest run" "**Latest run**: \`bash tests/bench/run_benchmark.sh" \
  "$(sed -n 2p <<<"$block" | cut -c1-50)"
check "README block holds the main table" 1 "$(grep -c '^| input | particles | tool | wall s |' <<<"$block")"
check "README block holds the targets table" 1 "$(grep -c '^| target | this run | |$' <<<"$block")"

# targets_table.sh: each verdict at its target's edge, on made-up figures.
table="$source_dir/tests/bench/targets_table.sh"
base=(wall64=0.25 "pairs64=0.25 0.24 0.26" rss64=0.75 iteration_fixed=15.0% iteration_calibrated=16.2%
      two_threads=1.80 "two_thread_pairs=1.8 1.79 1.81" paper_seconds=0.049 wall512=0.25 "pairs512=0.25 0.25 0.25"
      rss512=0.51 linearity=1.15)
verdicts() { bash "$table" "$@" | tail -n +3 | awk -F' [|] ' '{print $NF}' | sed 's/ |$//' | tr '\n' ' ' | sed 's/ $//'; }
check "every target at its edge is met" "met met met met met met met" "$(verdicts "${base[@]}")"
check "just past each edge" "**missed** **missed** **missed** **missed** **missed** **missed** **missed**" \
  "$(verdicts "${base[@]}" wall64=0.251 wall512=0.2501 rss512=0.76 linearity=1.16 iteration_fixed=15.1% \
     two_threads=1.79 paper_seconds=0.05)"
check "linearity is two-sided" "met **missed**" \
  "$(verdicts "${base[@]}" linearity=0.85 | cut -d' ' -f4) $(verdicts "${base[@]}" linearity=0.84 | cut -d' ' -f4)"
check "the worse RSS ratio decides" "**missed**" "$(verdicts "${base[@]}" rss64=0.80 rss512=0.5 | cut -d' ' -f3)"
check "a figure that is no number is missed" "**missed**" "$(verdicts "${base[@]}" two_threads=- | cut -d' ' -f6)"
# --quick: no 512x rows, linearity not measured, and the 1x RSS ratio (0.97) never counts.
quick=$(bash "$table" wall64=0.229 "pairs64=0.231" rss64=0.67 iteration_fixed=6.9% iteration_calibrated=11.5% \
  two_threads=1.86 "two_thread_pairs=1.86" paper_seconds=0.023)
check "quick table" "$(printf '%s\n' \
  "| target | this run | |" "| --- | --- | --- |" \
  "| wall time ≤ 0.25x vdb_tool's, 64x | 0.229 (pairs 0.231) | met |" \
  "| peak RSS ≤ 0.75x vdb_tool's | 64x 0.67 | met |" \
  "| per-particle time at 512x within 15% of 64x | not measured (--quick) | |" \
  "| one relaxation iteration ≤ 15% of the t = 0 run | 6.9% with r_0 held (11.5% with r_0 calibrated for each t) | met |" \
  "| two threads ≥ 1.8x one | 1.86x (pairs 1.86) | met |" \
  "| paper's frame (14,272 particles, t = 2) < 0.05 s of compute | 0.023 s | met |")" "$quick"
status=0
bash "$table" wall64=0.2 > /dev/null 2> "$work/err" || status=$?
check "a missing figure is refused" "2 targets_table.sh: missing pairs64" "$status $(cat "$work/err")"
# The README's table is the one targets_table.sh makes of the figures it shows.
readme_table=$(sed -n '/^| target | this run | |$/,/^| paper/p' "$source_dir/README.md")
check "README targets table: a header, its rule and seven targets" 9 "$(wc -l <<<"$readme_table")"

finish test_bench_scripts.sh

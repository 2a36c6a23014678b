#!/usr/bin/env bash
# ctest benchmark_update_readme: tests/bench/update_readme.sh replaces exactly the lines
# between the README's benchmark markers, refuses a README without them (one line, exit 2,
# the file untouched), and the repository's README.md holds the markers it needs.
#   usage: test_update_readme.sh SOURCE_DIR
set -euo pipefail
source_dir="$1"
script="$source_dir/tests/bench/update_readme.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
check() {  # check DESCRIPTION EXPECTED ACTUAL
  if [ "$2" != "$3" ]; then
    printf 'FAILED: %s\n--- expected\n%s\n--- actual\n%s\n' "$1" "$2" "$3" >&2
    failures=$((failures + 1))
  fi
}

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

if ((failures)); then echo "$failures check(s) failed" >&2; exit 1; fi
echo "update_readme.sh: all checks passed"

#!/usr/bin/env bash
# Put a benchmark summary into the README: replace the lines between the README's two marker
# lines with the summary file's lines, and leave every other line as it was.
#
#   bash tests/bench/update_readme.sh SUMMARY [README]    (README: README.md by default)
#
# SUMMARY is the summary.md that `run_benchmark.sh` writes (its --update-readme calls this).
# The markers are HTML comments, invisible in the rendered README:
#   <!-- benchmark summary: begin -->
#   <!-- benchmark summary: end -->
# The README is rewritten through a temporary file beside it and a rename, so an error leaves
# it as it was. Exit 2, with one line naming the file, if a file cannot be read or the README
# lacks its markers (or holds them more than once, or out of order).
set -euo pipefail

begin='<!-- benchmark summary: begin -->'
end='<!-- benchmark summary: end -->'
summary="${1:-}"
readme="${2:-README.md}"
fail() { echo "update_readme.sh: $*" >&2; exit 2; }

[ -n "$summary" ] || fail "usage: update_readme.sh SUMMARY [README]"
[ -f "$summary" ] && [ -r "$summary" ] || fail "cannot read the summary $summary"
[ -f "$readme" ] && [ -r "$readme" ] || fail "cannot read the README $readme"
[ -s "$summary" ] || fail "the summary $summary is empty"

begins=$(grep -cxF -- "$begin" "$readme" || true)
ends=$(grep -cxF -- "$end" "$readme" || true)
if [ "$begins" != 1 ] || [ "$ends" != 1 ]; then
  fail "$readme must hold the line '$begin' once and the line '$end' once after it (found $begins and $ends)"
fi
begin_line=$(grep -nxF -- "$begin" "$readme" | cut -d: -f1)
end_line=$(grep -nxF -- "$end" "$readme" | cut -d: -f1)
((begin_line < end_line)) || fail "$readme has '$end' before '$begin'"

temporary=$(mktemp "$(dirname "$readme")/.update_readme.XXXXXX")
trap 'rm -f "$temporary"' EXIT
{
  head -n "$begin_line" "$readme"
  cat "$summary"
  tail -n "+$end_line" "$readme"
} > "$temporary"
chmod --reference="$readme" "$temporary"
mv -f "$temporary" "$readme"
trap - EXIT
echo "update_readme.sh: $readme now shows $summary" >&2

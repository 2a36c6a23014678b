# Sourced by the benchmark's script tests: a scratch directory removed on exit ($work), and
# check DESCRIPTION EXPECTED ACTUAL, which reports a mismatch on stderr and counts it; end
# with finish NAME, which exits 1 if any check failed.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
check() {
  if [ "$2" != "$3" ]; then
    printf 'FAILED: %s\n--- expected\n%s\n--- actual\n%s\n' "$1" "$2" "$3" >&2
    failures=$((failures + 1))
  fi
}
finish() {
  if ((failures)); then echo "$1: $failures check(s) failed" >&2; exit 1; fi
  echo "$1: all checks passed"
}

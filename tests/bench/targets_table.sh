#!/usr/bin/env bash
# The targets table of a benchmark run (run_benchmark.sh's summary): each target of the
# performance issue, the run's figure and whether the run met it. Apart from the script so
# that its verdicts are tested on made-up figures (test_bench_scripts.sh).
#
#   bash tests/bench/targets_table.sh KEY=VALUE...
#
# Keys: wall64 pairs64 rss64 iteration_fixed ("8.3%") iteration_calibrated two_threads
# two_thread_pairs paper_seconds, and with the 512x input (not --quick) wall512 pairs512
# rss512 linearity. A missing key is an error (exit 2), not a figure of 0.
set -euo pipefail

declare -A v
for pair in "$@"; do
  [[ "$pair" == *=* ]] || { echo "targets_table.sh: expected KEY=VALUE, got '$pair'" >&2; exit 2; }
  v[${pair%%=*}]="${pair#*=}"
done
need() { for key in "$@"; do [ -n "${v[$key]+set}" ] || { echo "targets_table.sh: missing $key" >&2; exit 2; }; done; }
need wall64 pairs64 rss64 iteration_fixed iteration_calibrated two_threads two_thread_pairs paper_seconds
full=0
[ -n "${v[wall512]+set}" ] && { need pairs512 rss512 linearity; full=1; }

# verdict VALUE OP LIMIT [HIGH]: "met" or "**missed**"; OP le, lt, ge, or within (LIMIT <=
# VALUE <= HIGH). A value that is no number (a failed measurement) is missed.
verdict() {
  awk -v value="${1%\%}" -v op="$2" -v low="$3" -v high="${4:-0}" 'BEGIN {
    if (value !~ /^-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$/) ok = 0
    else if (op == "le") ok = value + 0 <= low + 0
    else if (op == "lt") ok = value + 0 < low + 0
    else if (op == "ge") ok = value + 0 >= low + 0
    else ok = value + 0 >= low + 0 && value + 0 <= high + 0
    printf "%s", ok ? "met" : "**missed**"}'
}

echo "| target | this run | |"
echo "| --- | --- | --- |"
echo "| wall time ≤ 0.25x vdb_tool's, 64x | ${v[wall64]} (pairs ${v[pairs64]}) | $(verdict "${v[wall64]}" le 0.25) |"
if ((full)); then
  echo "| wall time ≤ 0.25x vdb_tool's, 512x | ${v[wall512]} (pairs ${v[pairs512]}) | $(verdict "${v[wall512]}" le 0.25) |"
  rss_worst=$(printf '%s\n' "${v[rss64]}" "${v[rss512]}" | sort -g | tail -1)
  echo "| peak RSS ≤ 0.75x vdb_tool's | 64x ${v[rss64]}, 512x ${v[rss512]} | $(verdict "$rss_worst" le 0.75) |"
  echo "| per-particle time at 512x within 15% of 64x | ${v[linearity]} | $(verdict "${v[linearity]}" within 0.85 1.15) |"
else
  echo "| peak RSS ≤ 0.75x vdb_tool's | 64x ${v[rss64]} | $(verdict "${v[rss64]}" le 0.75) |"
  echo "| per-particle time at 512x within 15% of 64x | not measured (--quick) | |"
fi
echo "| one relaxation iteration ≤ 15% of the t = 0 run | ${v[iteration_fixed]} with r_0 held (${v[iteration_calibrated]} with r_0 calibrated for each t) | $(verdict "${v[iteration_fixed]}" le 15) |"
echo "| two threads ≥ 1.8x one | ${v[two_threads]}x (pairs ${v[two_thread_pairs]}) | $(verdict "${v[two_threads]}" ge 1.8) |"
echo "| paper's frame (14,272 particles, t = 2) < 0.05 s of compute | ${v[paper_seconds]} s | $(verdict "${v[paper_seconds]}" lt 0.05) |"

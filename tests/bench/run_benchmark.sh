#!/usr/bin/env bash
# Speed and memory of `nonbloppy mesh` against OpenVDB's own particle mesher, measured in one run
# on the same inputs: the real dam-break frame tiled into 1, 64 and 512 disjoint copies.
#
#   bash tests/bench/run_benchmark.sh [--quick] [--runs N] [--out DIR] [--keep-meshes] [--update-readme]
#
#   --quick   skip the 512x input (12.5M particles) and the t/threads scans run once each
#   --runs N  rounds over the inputs, each running both tools in turn on each input (default 3;
#             the median is kept)
#   --out DIR where the generated inputs, meshes and the report go (default /tmp/nonbloppy-bench)
#   --keep-meshes  keep both tools' last meshes in DIR; by default they are removed at the end
#             (2.1 GB after a full run, most of it the two 512x meshes), the inputs kept for the
#             next run
#   --update-readme  put the run's summary (DIR/summary.md: the machine, the commit, the main
#             table and the targets met or missed) into README.md between its benchmark
#             markers (tests/bench/update_readme.sh), so that the README shows the latest run
#             as it was measured, never copied by hand
#
# The peer is `vdb_tool` from Debian's libopenvdb-tools:
#   vdb_tool -read IN.ply -points2ls voxel=0.025 radius=2 width=3 -ls2mesh adapt=0 -write OUT.ply
# nonbloppy runs with voxel size 0.025, r_e = 0.1, c = 0.3, t = 2 and writes binary PLY too.
# On the 64x input the script also scans t (0, 1, 2, 4) and the thread count (1, 2), runs the
# faithful method's volume correction and smoothing (`--spacing`, with and without
# `--no-smooth`), meshes a six-frame sequence, and meshes the input tiled with the frame's id
# and velocity: with `--attributes all`, read from VTK, VTU, CSV and OpenVDB points, and
# written as OBJ; and it meshes the input from Python through the module, where it was built.
# Wall time, CPU time (user + system) and peak RSS come from GNU time. The report is markdown,
# printed and written to DIR/benchmark.md.
set -euo pipefail
cd "$(dirname "$0")/../.."

runs=3
quick=0
keep_meshes=0
update_readme=0
out=/tmp/nonbloppy-bench
while (($#)); do
  case "$1" in
    --quick) quick=1 ;;
    --runs) runs="$2"; shift ;;
    --out) out="$2"; shift ;;
    --keep-meshes) keep_meshes=1 ;;
    --update-readme) update_readme=1 ;;
    *) echo "run_benchmark.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done

bash tools/setup.sh >/dev/null
nonbloppy="$PWD/build/nonbloppy"
tile="$PWD/build/nonbloppy_tile"
frame="$PWD/tests/data/dam_break_frame_23_24389_particles.vtk"
mkdir -p "$out"
rm -f "$out"/*.usersys  # run_timed appends to them: this invocation's runs only
report="$out/benchmark.md"
: > "$report"
say() { printf '%s\n' "$*" | tee -a "$report"; }

nb_args=(--voxel-size 0.025 --radius 0.1 --blend 0.3 --iterations 2)

# run_timed LOG CMD...: runs CMD, appends "wall cpu rss_kb" to LOG; CMD's stdout goes to LOG.out.
# Every timed run writes a new file (the caller removes the old one first, untimed): replacing
# an existing 100 MB mesh adds its deletion to the run, 0.3 s on this machine's ext4 (mounted
# with discard), which measures the file system rather than either tool.
# Each timed run also starts with no dirty page cache (an untimed `sync`): vdb_tool writes its
# ~100 MB mesh through the page cache and exits before the kernel has flushed it, and that
# flush otherwise ran during the next run (nonbloppy's; 64x, 3 pairs: 1.92-2.28 s after
# vdb_tool, 1.85-2.04 s with a sync between). nonbloppy's own meshes leave nothing to flush
# (direct I/O).
run_timed() {
  local log="$1"; shift
  sync
  /usr/bin/time -f "%e %U %S %M" -o "$log.time" "$@" > "$log.out" 2> "$log.err"
  awk '{printf "%s %.2f %s\n", $1, $2 + $3, $4}' "$log.time" >> "$log"
  # User and system seconds apart: the system time (page faults, mostly) need not grow as
  # the user time does, and tells the program's own cost from the kernel's.
  awk '{printf "%s %s\n", $2, $3}' "$log.time" >> "$log.usersys"
}

# compute_time OUT: the stage times nonbloppy printed to OUT, without reading and writing.
compute_time() {
  sed -n '/^timings/,$p' "$1" | grep -vE 'read particles|write |total|timings' \
    | awk '{for (i = 1; i <= NF; ++i) if ($i == "s") s += $(i - 1)} END {print s}'
}

# median COLUMN FILE
median() { cut -d' ' -f"$1" "$2" | sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

declare -A copies_of=([1]=1 [64]=4 [512]=8)
sizes=(1 64 512)
((quick)) && sizes=(1 64)

# What the run measured: the command, when, on what, and which code (a commit with local
# changes says so: its figures are not that commit's; changes to the README and docs/, which
# --update-readme makes itself, do not count).
command_line="bash tests/bench/run_benchmark.sh$( ((quick)) && printf ' --quick' || true) --runs $runs"
started=$(date -u '+%Y-%m-%d %H:%M UTC')
cpu_model=$(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo)
flags=$(awk -F': ' '/^flags/ {print " " $2 " "; exit}' /proc/cpuinfo)
case "$flags" in *" avx512f "*) isa="AVX-512" ;; *" avx2 "*) isa="AVX2" ;; *) isa="no AVX2" ;; esac
machine="$(nproc) cores of ${cpu_model:-an unnamed CPU} ($isa), $(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)"
commit=$(git rev-parse --short HEAD 2>/dev/null || echo "no git")
[ -n "$(git status --porcelain --untracked-files=no -- . ':!README.md' ':!docs' 2>/dev/null)" ] && commit="$commit with local changes"

say "# nonbloppy benchmark"
say ""
say "Command: \`$command_line\`, $started, commit $commit, on $machine."
say "Input: \`tests/data/dam_break_frame_23_24389_particles.vtk\` tiled by \`nonbloppy_tile --copies N\` (binary PLY)."
say "nonbloppy: \`mesh IN -o OUT.ply ${nb_args[*]}\`; vdb_tool: \`-points2ls voxel=0.025 radius=2 width=3 -ls2mesh adapt=0\`."
say "Median of $runs runs each, in rounds over the inputs, the two tools alternating."
say ""
main_header=("| input | particles | tool | wall s | CPU s | peak RSS MiB | particles/s | wall ratio | RSS ratio |"
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
main_rows=()
# group_digits N: N with thousands separated by commas (12487168 -> 12,487,168).
group_digits() { printf '%s' "$1" | sed ':a;s/\B[0-9]\{3\}\>/,&/;ta'; }
say "${main_header[0]}"
say "${main_header[1]}"

declare -A nb_wall nb_cpu pair_ratios wall_ratio_of rss_ratio_of
for size in "${sizes[@]}"; do
  input="$out/dam_break_x${size}.ply"
  [ -s "$input" ] || "$tile" "$frame" "$input" --copies "${copies_of[$size]}" > /dev/null
  rm -f "$out/nb_$size" "$out/vt_$size" "$out/nb_$size.compute"
done
# Rounds over every size, rather than all runs of one size then the next: the machine's speed
# drifts over minutes, and the linearity compares nonbloppy at 512x with itself at 64x, so
# each round measures both sizes within a minute or two of each other.
for ((r = 0; r < runs; ++r)); do
  for size in "${sizes[@]}"; do
    input="$out/dam_break_x${size}.ply"
    rm -f "$out/nb_x$size.ply" "$out/vt_x$size.ply"
    run_timed "$out/nb_$size" "$nonbloppy" mesh "$input" -o "$out/nb_x$size.ply" "${nb_args[@]}"
    compute_time "$out/nb_$size.out" >> "$out/nb_$size.compute"
    run_timed "$out/vt_$size" vdb_tool -read "$input" -points2ls voxel=0.025 radius=2 width=3 \
      -ls2mesh adapt=0 -write "$out/vt_x$size.ply"
  done
done
for size in "${sizes[@]}"; do
  particles=$(( 24389 * size ))
  nbw=$(median 1 "$out/nb_$size"); nbc=$(median 2 "$out/nb_$size"); nbm=$(median 3 "$out/nb_$size")
  vtw=$(median 1 "$out/vt_$size"); vtc=$(median 2 "$out/vt_$size"); vtm=$(median 3 "$out/vt_$size")
  nb_wall[$size]=$nbw
  nb_cpu[$size]=$nbc
  # Three decimals: the issue's target is 0.25, and 0.248 must not print as 0.25.
  ratio_wall=$(awk -v a="$nbw" -v b="$vtw" 'BEGIN {printf "%.3f", a / b}')
  # Each run of one tool and the other's right after it make a pair that a slow spell of the
  # machine hits alike: their ratios tell how far the ratio of medians can be trusted.
  pair_ratios[$size]=$(paste -d' ' "$out/nb_$size" "$out/vt_$size" \
    | awk '{printf "%s%.3f", (NR > 1 ? " " : ""), $1 / $4}')
  ratio_rss=$(awk -v a="$nbm" -v b="$vtm" 'BEGIN {printf "%.2f", a / b}')
  wall_ratio_of[$size]=$ratio_wall
  rss_ratio_of[$size]=$ratio_rss
  rate() { awk -v n="$particles" -v t="$1" 'BEGIN {printf "%.3gM", n / t / 1e6}'; }
  main_rows+=("| ${size}x | $(group_digits "$particles") | nonbloppy | $nbw | $nbc | $(group_digits $((nbm / 1024))) | $(rate "$nbw") | $ratio_wall | $ratio_rss |"
               "| ${size}x | $(group_digits "$particles") | vdb_tool | $vtw | $vtc | $(group_digits $((vtm / 1024))) | $(rate "$vtw") | | |")
  say "${main_rows[-2]}"
  say "${main_rows[-1]}"
done

say ""
for size in "${sizes[@]}"; do
  say "Wall ratio of each alternating pair, ${size}x: ${pair_ratios[$size]}."
done
say ""
# The linearity target's figure: per-particle wall time at 512x over that at 64x.
linearity=-
if [ -n "${nb_wall[512]:-}" ]; then
  linearity=$(awk -v a="${nb_wall[512]}" -v b="${nb_wall[64]}" 'BEGIN {printf "%.2f", (a / 512) / (b / 64)}')
fi
say "Per-particle wall time, 512x relative to 64x (1.00 = linear): $(
  if [ "$linearity" != - ]; then
    printf '%s' "$linearity"
    printf '; per-particle CPU time (user + system): '
    awk -v a="${nb_cpu[512]}" -v b="${nb_cpu[64]}" 'BEGIN {printf "%.2f", (a / 512) / (b / 64)}'
    printf '; each round (512x and 64x runs of one round): '
    paste -d' ' "$out/nb_512" "$out/nb_64" | awk '{printf "%s%.2f", (NR > 1 ? " " : ""), ($1 / 512) / ($4 / 64)}'
    # growth COLUMN TOOL: the per-particle growth of TOOL's (nb, vt) user (1) or system (2) time.
    growth() { awk -v a="$(median "$1" "$out/${2}_512.usersys")" -v b="$(median "$1" "$out/${2}_64.usersys")" \
                 'BEGIN {if (b > 0) printf "%.2f", (a / 512) / (b / 64); else printf "-"}'; }
    printf '; user time alone: %s (vdb_tool: %s); system time alone: %s (vdb_tool: %s)' \
      "$(growth 1 nb)" "$(growth 1 vt)" "$(growth 2 nb)" "$(growth 2 vt)"
  else echo "not measured (--quick)"; fi)"

# Stages of the last 64x run, as nonbloppy prints them.
say ""
say "nonbloppy stages, 64x input (last run):"
say ""
say '```'
sed -n '/^timings/,$p' "$out/nb_64.out" | tee -a "$report"
say '```'

# Scaling with t and with threads on the 64x input.
scan_runs=$runs
((quick)) && scan_runs=1
# scan_file LABEL IN OUT ARGS...: one timed run of nonbloppy meshing IN into OUT with ARGS.
scan_file() {
  local log="$out/scan_$1" input="$2" output="$3"; shift 3
  rm -f "$output"
  run_timed "$log" "$nonbloppy" mesh "$input" -o "$output" "$@"
}
scan_once() { local label="$1"; shift; scan_file "$label" "$out/dam_break_x64.ply" "$out/scan.ply" "$@"; }
# stage_seconds OUT STAGE: the wall seconds nonbloppy printed for STAGE ("read particles").
stage_seconds() {
  sed -n '/^timings/,$p' "$1" | awk -v name="$2" '{line = $0; sub(/^ +/, "", line)
    if (index(line, name " ") == 1) for (i = 1; i <= NF; ++i) if ($i == "s") {print $(i - 1); exit}}'
}
# The settings take turns, run after run, so that a slow spell of the machine (seconds to
# minutes here) hits them alike: when each setting ran its repetitions back to back, two runs
# of the script measured t = 2 slower than t = 4 (1.79 / 1.77 s) and t = 0 slower than t = 1
# (1.46 / 1.43 s).
# r_0 is calibrated for the relaxed surface, so each t also extracts a surface of another size
# (more vertices at larger t). With r_0 held at the t = 2 value, only the iterations vary.
r0=$(awk '$1 == "threshold" {print $3}' "$out/nb_64.out")
declare -A t_wall t_fixed
for t in 0 1 2 4; do rm -f "$out/scan_t$t" "$out/scan_tfixed$t"; done
for ((r = 0; r < scan_runs; ++r)); do
  for t in 0 1 2 4; do
    scan_once "t$t" --voxel-size 0.025 --radius 0.1 --blend 0.3 --iterations "$t"
    scan_once "tfixed$t" --voxel-size 0.025 --radius 0.1 --blend 0.3 --threshold "$r0" --iterations "$t"
  done
done
# One and two threads in pairs of adjacent runs, the order swapped every other pair, at least
# seven pairs: the machine's slow spells last seconds, so a ratio of two medians taken from
# different rounds strayed (2026-12-04: medians 3.02 / 1.97 s = 1.53x while the three pairs
# gave 1.41, 1.71 and 1.72), and one pair of five can still fall far out (2026-12-05: 1.32x
# beside 1.61-1.78x), which moves a median of five more than one of seven. Each pair's stage
# times are kept for the per-stage ratios.
thread_pairs=$(( scan_runs < 7 ? 7 : scan_runs ))
((quick)) && thread_pairs=1
rm -f "$out/scan_threads1" "$out/scan_threads2" "$out/scan_threads_stages"
for ((r = 0; r < thread_pairs; ++r)); do
  order=(1 2); ((r % 2)) && order=(2 1)
  for threads in "${order[@]}"; do
    scan_once "threads$threads" "${nb_args[@]}" --threads "$threads"
    # threads, pair, stage, wall seconds, cores busy (the summary's last column)
    sed -n '/^timings/,$p' "$out/scan_threads$threads.out" | grep ' s ' \
      | awk -v t="$threads" -v r="$r" '{
          for (i = 2; i <= NF; ++i) if ($i == "s") break
          name = $1; for (k = 2; k < i - 1; ++k) name = name " " $k
          print t "\t" r "\t" name "\t" $(i - 1) "\t" $NF}' \
      >> "$out/scan_threads_stages"
  done
done
say ""
say "| 64x input | wall s |"
say "| --- | --- |"
for t in 0 1 2 4; do
  t_wall[$t]=$(median 1 "$out/scan_t$t")
  say "| t = $t | ${t_wall[$t]} |"
done
for t in 0 1 2 4; do
  t_fixed[$t]=$(median 1 "$out/scan_tfixed$t")
  say "| t = $t, --threshold $r0 (the t = 2 value) | ${t_fixed[$t]} |"
done
threads1=$(median 1 "$out/scan_threads1")
threads2=$(median 1 "$out/scan_threads2")
say "| t = 2, --threads 1 (median of $thread_pairs) | $threads1 |"
say "| t = 2, --threads 2 (median of $thread_pairs) | $threads2 |"
say ""
per_iteration() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.1f%%", 100 * (a - b) / 4 / b}'; }
iteration_fixed=$(per_iteration "${t_fixed[4]}" "${t_fixed[0]}")
iteration_calibrated=$(per_iteration "${t_wall[4]}" "${t_wall[0]}")
say "Each relaxation iteration costs $iteration_fixed of the t = 0 run with r_0 fixed ($iteration_calibrated with r_0 calibrated for each t, which also grows the surface)."
# thread_ratios NAME: one-thread over two-thread time of each pair for stage NAME ("wall":
# the whole run), then their median.
thread_ratios() {
  if [ "$1" = wall ]; then
    paste -d' ' "$out/scan_threads1" "$out/scan_threads2" | awk '{print $1 / $4}'
  else
    awk -F'\t' -v name="$1" '$3 == name {v[$1, $2] = $4; n = $2 + 1}
      END {for (r = 0; r < n; ++r) if (v[2, r] > 0) print v[1, r] / v[2, r]}' "$out/scan_threads_stages"
  fi
}
# median_of [FORMAT]: the median of the numbers on standard input (two decimals by default).
median_of() { sort -g | awk -v f="${1:-%.2f}" '{v[NR] = $1} END {if (NR) printf f, (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2)}'; }
two_threads=$(thread_ratios wall | median_of)
two_thread_pairs=$(thread_ratios wall | awk '{printf "%s%.2f", (NR > 1 ? " " : ""), $1}')
say "Two threads against one, median of the $thread_pairs pairs' ratios: ${two_threads}x (pairs: $two_thread_pairs). Per stage:"
say ""
# Cores busy: the stage's process CPU time over its wall time, as nonbloppy prints it. Below 2
# at two threads, a stage waits on something serial; at ~2 with a ratio below 2, each core
# does its work more slowly when both run (shared caches, memory, clock).
say "| stage | 1 thread s | 2 threads s | ratio (median of pairs) | cores busy at 2 threads |"
say "| --- | --- | --- | --- | --- |"
while IFS= read -r stage; do
  one=$(awk -F'\t' -v name="$stage" '$1 == 1 && $3 == name {print $4}' "$out/scan_threads_stages" | median_of %.3f)
  two=$(awk -F'\t' -v name="$stage" '$1 == 2 && $3 == name {print $4}' "$out/scan_threads_stages" | median_of %.3f)
  cores=$(awk -F'\t' -v name="$stage" '$1 == 2 && $3 == name {print $5}' "$out/scan_threads_stages" | median_of)
  say "| $stage | $one | $two | $(thread_ratios "$stage" | median_of) | $cores |"
done < <(awk -F'\t' '$1 == 1 && $2 == 0 {print $3}' "$out/scan_threads_stages")

# With the spacing given, the faithful method also corrects the volume and smooths the
# surface (docs/fidelity.md): the fidelity of the README's table, at a cost the runs above do
# not show. The two settings take turns, as in the t scan.
spacing=$(awk '$1 == "spacing" {print $3}' "$out/nb_64.out")
rm -f "$out/scan_spacing" "$out/scan_nosmooth" "$out/scan_spacing.smooth"
for ((r = 0; r < scan_runs; ++r)); do
  scan_once spacing "${nb_args[@]}" --spacing "$spacing"
  stage_seconds "$out/scan_spacing.out" "smooth surface" >> "$out/scan_spacing.smooth"
  scan_once nosmooth "${nb_args[@]}" --spacing "$spacing" --no-smooth
done
say ""
say "With the spacing given (\`--spacing $spacing\`, the value estimated above): volume correction and smoothing, median of $scan_runs runs each, alternating:"
say ""
say "| 64x input | wall s | peak RSS MiB | smooth surface s |"
say "| --- | --- | --- | --- |"
spacing_wall=$(median 1 "$out/scan_spacing"); spacing_rss=$(( $(median 3 "$out/scan_spacing") / 1024 ))
spacing_smooth=$(median_of %.3f < "$out/scan_spacing.smooth"); nosmooth_wall=$(median 1 "$out/scan_nosmooth")
say "| \`--spacing $spacing\` | $spacing_wall | $spacing_rss | $spacing_smooth |"
say "| \`--spacing $spacing --no-smooth\` | $nosmooth_wall | $(( $(median 3 "$out/scan_nosmooth") / 1024 )) | - |"
rm -f "$out/scan_spacing.smooth"

# Sequences: one `mesh` call over frames, as a cache is meshed, against the single-frame runs
# above. Every frame is the 64x input (symbolic links), so each frame costs what one run
# measured. By default a frame is written while the next one is meshed; --frame-jobs 2 meshes
# two frames at once, each with both threads.
seq_frames=6
mkdir -p "$out/sequence"
for ((f = 1; f <= seq_frames; ++f)); do ln -sf "$out/dam_break_x64.ply" "$out/sequence/in_$f.ply"; done
rm -f "$out/seq_behind" "$out/seq_jobs2"
for ((r = 0; r < scan_runs; ++r)); do
  for mode in behind jobs2; do
    rm -f "$out"/sequence/out_*.ply
    extra=(); [ "$mode" = jobs2 ] && extra=(--frame-jobs 2)
    run_timed "$out/seq_$mode" "$nonbloppy" mesh "$out/sequence/in_{}.ply" -o "$out/sequence/out_{}.ply" \
      --frames "1-$seq_frames" "${nb_args[@]}" "${extra[@]}"
  done
done
rm -f "$out"/sequence/out_*.ply
say ""
say "Sequences: $seq_frames frames of the 64x input in one call (\`mesh 'in_{}.ply' -o 'out_{}.ply' --frames 1-$seq_frames\`), median of $scan_runs runs, against $seq_frames single-frame runs (the 64x rows above):"
say ""
say "| $seq_frames frames of 64x | wall s | per frame s | peak RSS MiB | per frame / one-frame run | per frame / vdb_tool run |"
say "| --- | --- | --- | --- | --- | --- |"
vt64=$(median 1 "$out/vt_64")
sequence_row() {  # sequence_row LABEL WALL RSS_KB
  awk -v label="$1" -v w="$2" -v m="$3" -v n="$seq_frames" -v one="${nb_wall[64]}" -v vt="$vt64" \
    'BEGIN {printf "| %s | %.2f | %.3f | %d | %.2f | %.3f |\n", label, w, w / n, m / 1024, w / n / one, w / n / vt}' \
    | tee -a "$report"
}
sequence_row "one frame at a time, written while the next is meshed" "$(median 1 "$out/seq_behind")" "$(median 3 "$out/seq_behind")"
sequence_row "--frame-jobs 2" "$(median 1 "$out/seq_jobs2")" "$(median 3 "$out/seq_jobs2")"
# per_frame LOG: a sequence's wall time per frame over the single-frame run's (the summary's).
per_frame() { awk -v w="$(median 1 "$1")" -v n="$seq_frames" -v one="${nb_wall[64]}" 'BEGIN {printf "%.2f", w / n / one}'; }
sequence_behind=$(per_frame "$out/seq_behind"); sequence_jobs2=$(per_frame "$out/seq_jobs2")
sequence_behind_rss=$(( $(median 3 "$out/seq_behind") / 1024 )); sequence_jobs2_rss=$(( $(median 3 "$out/seq_jobs2") / 1024 ))
sequence_row "$seq_frames separate runs" "$(awk -v w="${nb_wall[64]}" -v n="$seq_frames" 'BEGIN {print w * n}')" "$(median 3 "$out/nb_64")"

# Attributes and file formats (no targets): the 64x input tiled with the frame's id (uint32)
# and velocity (3 x float32), as a simulation writes them; meshed without and with
# `--attributes all`, read from each format `convert` writes that keeps them, and the mesh
# written as OBJ against PLY. The runs take turns, as in the t scan.
attr_input="$out/dam_break_x64_attributes.ply"
[ -s "$attr_input" ] || "$tile" "$frame" "$attr_input" --copies 4 --attributes > /dev/null
megabytes() { awk -v b="$1" 'BEGIN {printf "%.0f", b / 1e6}'; }
attr_input_mb=$(megabytes "$(stat -c %s "$attr_input")")
formats=(vtk vtu csv vdb)
for format in "${formats[@]}"; do
  [ -s "${attr_input%.ply}.$format" ] || "$nonbloppy" convert -q "$attr_input" "${attr_input%.ply}.$format"
done
labels=(attr_none attr_all obj read_ply "${formats[@]/#/read_}")
for label in "${labels[@]}"; do rm -f "$out/scan_$label" "$out/scan_$label.stage"; done
for ((r = 0; r < scan_runs; ++r)); do
  scan_file attr_none "$attr_input" "$out/scan.ply" "${nb_args[@]}"
  stage_seconds "$out/scan_attr_none.out" "write mesh" >> "$out/scan_attr_none.stage"
  stage_seconds "$out/scan_attr_none.out" "read particles" >> "$out/scan_read_ply.stage"
  ply_bytes=$(stat -c %s "$out/scan.ply")
  scan_file attr_all "$attr_input" "$out/scan.ply" "${nb_args[@]}" --attributes all
  stage_seconds "$out/scan_attr_all.out" "interpolate attributes" >> "$out/scan_attr_all.stage"
  scan_file obj "$attr_input" "$out/scan.obj" "${nb_args[@]}"
  stage_seconds "$out/scan_obj.out" "write mesh" >> "$out/scan_obj.stage"
  obj_bytes=$(stat -c %s "$out/scan.obj")
  for format in "${formats[@]}"; do
    scan_file "read_$format" "${attr_input%.ply}.$format" "$out/scan.ply" "${nb_args[@]}"
    stage_seconds "$out/scan_read_$format.out" "read particles" >> "$out/scan_read_$format.stage"
  done
done
rm -f "$out/scan.obj"
ply_read=$(median_of %.3f < "$out/scan_read_ply.stage")
attr_without=$(median 1 "$out/scan_attr_none"); attr_with=$(median 1 "$out/scan_attr_all")
attr_interpolate=$(median_of %.3f < "$out/scan_attr_all.stage")
write_ply=$(median_of %.3f < "$out/scan_attr_none.stage"); write_obj=$(median_of %.3f < "$out/scan_obj.stage")
say ""
say "Attributes and formats: the 64x input with the frame's \`id\` (uint32) and \`velocity\` (3 x float32), median of $scan_runs runs each, alternating:"
say ""
say "| 64x input with id and velocity | wall s | stage s |"
say "| --- | --- | --- |"
say "| binary PLY ($attr_input_mb MB), the attributes not carried | $attr_without | read particles $ply_read; write mesh (PLY, $(megabytes "$ply_bytes") MB) $write_ply |"
say "| \`--attributes all\` | $attr_with | interpolate attributes $attr_interpolate |"
say "| \`-o mesh.obj\` | $(median 1 "$out/scan_obj") | write mesh (OBJ, $(megabytes "$obj_bytes") MB) $write_obj |"
read_figures="binary PLY $ply_read s ($attr_input_mb MB)"
declare -A format_names=([vtk]="legacy VTK" [vtu]="VTU" [csv]="CSV" [vdb]="OpenVDB points")
for format in "${formats[@]}"; do
  bytes=$(stat -c %s "${attr_input%.ply}.$format")
  seconds=$(median_of %.3f < "$out/scan_read_$format.stage")
  say "| ${format_names[$format]} ($(megabytes "$bytes") MB) | $(median 1 "$out/scan_read_$format") | read particles $seconds |"
  read_figures="$read_figures, ${format_names[$format]} $seconds s ($(megabytes "$bytes") MB)"
done
for label in "${labels[@]}"; do rm -f "$out/scan_$label.stage"; done

# From Python (no target): the same mesh made by a script through the module (read_particles,
# build_surface, Mesh.write), alternating with the tool; the two meshes must be the same bytes.
python_module=$(ls build/python/nonbloppy.*.so 2>/dev/null | head -1)
python_figures=""
if [ -n "$python_module" ] && [ -x /usr/bin/python3 ]; then
  rm -f "$out/scan_py_tool" "$out/scan_py"
  for ((r = 0; r < scan_runs; ++r)); do
    scan_once py_tool "${nb_args[@]}"
    rm -f "$out/py.ply"
    PYTHONPATH="$PWD/build/python" run_timed "$out/scan_py" /usr/bin/python3 tests/bench/mesh_from_python.py \
      "$out/dam_break_x64.ply" "$out/py.ply"
  done
  cmp -s "$out/scan.ply" "$out/py.ply" && same="the same bytes" || same="**different bytes**"
  rm -f "$out/py.ply"
  py_wall=$(median 1 "$out/scan_py"); py_tool_wall=$(median 1 "$out/scan_py_tool")
  py_rss=$(( $(median 3 "$out/scan_py") / 1024 )); py_tool_rss=$(( $(median 3 "$out/scan_py_tool") / 1024 ))
  say ""
  say "From Python (\`tests/bench/mesh_from_python.py\`: read_particles, build_surface with the same parameters, Mesh.write), the 64x input, median of $scan_runs runs each, alternating with the tool: $py_wall s and $py_rss MiB against $py_tool_wall s and $py_tool_rss MiB, $same."
  python_figures="From Python (the module, \`tests/bench/mesh_from_python.py\`): $py_wall s and $py_rss MiB against the tool's $py_tool_wall s and $py_tool_rss MiB in the same turns, $same."
fi

# The paper's figure: 14,272 particles, t = 2, about 15 s on a 2008 desktop. Compute time of the
# 1x frame (24,389 particles; stages without reading and writing) scaled to 14,272 particles.
# A frame this small computes in under 0.1 s, where one run in three or four is 20-40% slower
# (the other tool's run just before, the page cache): nonbloppy alone, eleven runs.
paper_runs=11
rm -f "$out/nb_paper.compute"
for ((r = 0; r < paper_runs; ++r)); do
  rm -f "$out/nb_paper.ply"
  "$nonbloppy" mesh "$out/dam_break_x1.ply" -o "$out/nb_paper.ply" "${nb_args[@]}" > "$out/nb_paper.out"
  compute_time "$out/nb_paper.out" >> "$out/nb_paper.compute"
done
compute=$(median 1 "$out/nb_paper.compute")
say ""
paper_seconds=$(awk -v c="$compute" 'BEGIN {printf "%.3f", c * 14272 / 24389}')
say "Paper comparison: the 24,389-particle frame computes in ${compute} s (stages other than reading and writing, 2 threads, median of $paper_runs runs of nonbloppy alone; each: $(tr '\n' ' ' < "$out/nb_paper.compute")s), that is $paper_seconds s for 14,272 particles (paper: about 15 s, t = 2)."

# The summary: what the README shows (--update-readme), also at the end of the report: the
# run, the main table, and each target of the performance issue with its figure in this run
# and whether this run met it (targets_table.sh).
figures=(wall64="${wall_ratio_of[64]}" pairs64="${pair_ratios[64]}" rss64="${rss_ratio_of[64]}"
         iteration_fixed="$iteration_fixed" iteration_calibrated="$iteration_calibrated"
         two_threads="$two_threads" two_thread_pairs="$two_thread_pairs" paper_seconds="$paper_seconds")
if [ "$linearity" != - ]; then
  figures+=(wall512="${wall_ratio_of[512]}" pairs512="${pair_ratios[512]}" rss512="${rss_ratio_of[512]}"
            linearity="$linearity")
fi
summary="$out/summary.md"
{
  echo "**Latest run**: \`$command_line\`, $started, commit $commit, on $machine."
  echo "$( ((runs == 1)) && echo "One run" || echo "Medians of $runs runs"), the two tools alternating on each input (the dam-break frame tiled into"
  echo "disjoint copies, binary PLY); nonbloppy \`${nb_args[*]}\`, vdb_tool"
  echo "\`-points2ls voxel=0.025 radius=2 width=3 -ls2mesh adapt=0\`."
  echo ""
  printf '%s\n' "${main_header[@]}" "${main_rows[@]}"
  echo ""
  bash tests/bench/targets_table.sh "${figures[@]}"
  echo ""
  # Measured in the same run, with no target: what --spacing adds, and a sequence's frames.
  echo "Also measured on the 64x input (no targets): with \`--spacing $spacing\` (volume correction"
  echo "and smoothing) $spacing_wall s and $spacing_rss MiB, $spacing_smooth s of it the smoothing, $nosmooth_wall s with"
  echo "\`--no-smooth\`; $seq_frames frames in one call, each written while the next is meshed, $sequence_behind of a"
  echo "single-frame run per frame at $sequence_behind_rss MiB, and $sequence_jobs2 with \`--frame-jobs 2\` at $sequence_jobs2_rss MiB."
  echo "With the frame's \`id\` and \`velocity\` tiled along: $attr_with s with \`--attributes all\` against"
  echo "$attr_without s without, $attr_interpolate s of it interpolating; the mesh written as OBJ ($(megabytes "$obj_bytes") MB) in $write_obj s"
  echo "against PLY's ($(megabytes "$ply_bytes") MB) $write_ply s; the particles read as $read_figures."
  [ -z "$python_figures" ] || echo "$python_figures"
} > "$summary"
say ""
say "## Summary"
say ""
tee -a "$report" < "$summary"
if ((update_readme)); then bash tests/bench/update_readme.sh "$summary" README.md; fi
if ((!keep_meshes)); then
  rm -f "$out"/nb_x*.ply "$out"/vt_x*.ply "$out/scan.ply" "$out/nb_paper.ply"
fi
echo "report: $report" >&2

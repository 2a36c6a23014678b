#!/usr/bin/env bash
# ctest tile_particles: nonbloppy_tile, which makes the benchmark's inputs. Copy (0, 0, 0) is
# the input's particles unmoved, the copies together hold N^3 times as many, the bounding box
# grows by (N - 1) steps of the input's extent plus the gap, --attributes keeps each
# attribute's type and values, and bad options end in one line, exit 1 and no file.
#   usage: test_tile.sh NONBLOPPY_TILE NONBLOPPY SOURCE_DIR
set -euo pipefail
tile="$1"
nonbloppy="$2"
frame="$3/tests/data/dam_break_frame_23_24389_particles.vtk"
source "$(dirname "$0")/check.sh"  # $work, check, finish
# json FILE: what `inspect --json` says of FILE.
json() { "$nonbloppy" inspect --json "$1"; }

"$tile" "$frame" "$work/plain.ply" --copies 2 > /dev/null
"$tile" "$frame" "$work/kept.ply" --copies 2 --attributes > /dev/null
json "$frame" > "$work/frame.json"
json "$work/plain.ply" > "$work/plain.json"
json "$work/kept.ply" > "$work/kept.json"
check "particle count" '"particles": 195112,' "$(grep -o '"particles": [0-9]*,' "$work/kept.json")"
check "no attributes by default" '"attributes": [],' "$(tr -d '\n ' < "$work/plain.json" | grep -o '"attributes":\[\],' | sed 's/:/: /')"
# The attributes as the input holds them: the same names, types and ranges.
attributes() { sed -n '/"attributes"/,/^  \]/p' "$1"; }
check "attributes kept" "$(attributes "$work/frame.json")" "$(attributes "$work/kept.json")"
# Copy (0, 0, 0) first, unmoved: the first 24,389 positions are the input's, bit for bit.
"$nonbloppy" convert -q "$frame" "$work/frame.xyz" 2> /dev/null  # (attributes dropped, as it warns)
"$nonbloppy" convert -q "$work/kept.ply" "$work/kept.xyz" 2> /dev/null
check "first copy unmoved" "$(md5sum < "$work/frame.xyz")" "$(head -c $((24389 * 12)) "$work/kept.xyz" | md5sum)"
# The box's far corner: one step (the input's extent plus the 0.05 gap) beyond the input's.
corner() { tr -d '\n ' < "$1" | grep -o "\"$2\":\[[^]]*\]" | head -1 | awk -F'[][,]' '{print $2, $3, $4}'; }
read -r x0 y0 z0 <<< "$(corner "$work/frame.json" min)"
read -r x1 y1 z1 <<< "$(corner "$work/frame.json" max)"
check "far corner" "$(awk -v a="$x0 $y0 $z0" -v b="$x1 $y1 $z1" 'BEGIN {split(a, lo, " "); split(b, hi, " ")
    for (i = 1; i <= 3; ++i) printf "%.5f ", 2 * hi[i] - lo[i] + 0.05}')" \
  "$(corner "$work/kept.json" max | awk '{printf "%.5f %.5f %.5f ", $1, $2, $3}')"
# Bad options: one line, exit 1, nothing written.
set +e
"$tile" "$frame" "$work/bad.ply" --copies 0 2> "$work/err"; status=$?
set -e
check "bad --copies exit" 1 "$status"
check "bad --copies message" "nonbloppy_tile: --copies must be an integer in [1,64], got '0'" "$(cat "$work/err")"
check "bad --copies leaves no file" "" "$(ls "$work" | grep bad || true)"
finish test_tile.sh

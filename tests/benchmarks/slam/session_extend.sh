#!/usr/bin/env bash
# Map sessions, extend mode: map the first part of a keygrid-sim loop with keygrid-slam --map,
# then run a second part that starts where the stored map has never looked with
# --load-map FILE (no --localize): it maps on in a frame of its own and is merged into the
# stored map when loop closing finds a place both know. Compared, in the same run, with one
# keygrid-slam run over the whole sequence. Cases (keygrid-sim scenes, 2 m texture tiles):
#   corridor  config/sim/corridor_loop.ini (1020 frames): map frames 0-449, extend with
#             frames 600-1019 (back at the start from about frame 950)
#   room      config/sim/room_loop.ini (450): map frames 0-149, extend with frames 250-449
#   office    config/sim/office_loop.ini (3300): map frames 1650-3299, extend with frames
#             400-1899 (unseen until frame 1650, then 250 frames in the mapped part)
# Prints per case: how the second run started, maps merged, the frame of the merge, ATE of
# the merged keyframes (keyframes.txt, one fit against ground truth) beside the single run's,
# and the second run's frames in the frame the first run fixed (keygrid-eval --map-run-gt).
#
#   tests/benchmarks/slam/session_extend.sh [--build DIR] [--out DIR] [--sim DIR]
#       [--cases "corridor room office"] [--help]
#   --sim DIR   folder with keygrid-sim renders DIR/<scene>/{tum,groundtruth.txt}, made there
#               when missing (default: OUT/sim)
# Results: doc/evaluation.md, "Map sessions".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
out=""
sim=""
cases="corridor room office"
kg_parse_args --build=build --out=out --sim=sim --cases=cases -- "$@"
build="$(kg_build_dir "$build" keygrid-sim keygrid-slam keygrid-eval)" || exit 2
[ -n "$out" ] || out="$(mktemp -d)"
[ -n "$sim" ] || sim="$out/sim"
mkdir -p "$out" "$sim"
bin="$build/bin"

# run_case NAME SCENE MAP_FROM MAP_FRAMES EXTEND_FROM EXTEND_FRAMES (0: to the end)
run_case() {
  local name="$1" scene="$2" mapFrom="$3" mapFrames="$4" from="$5" frames="$6"
  local s="$sim/$scene" d="$out/$name"
  [ -f "$s/groundtruth.txt" ] || "$bin/keygrid-sim" --quiet --scene "$root/config/sim/$scene.ini" --output "$s" \
    --voxel-resolution 0 --floorplan-resolution 0
  rm -rf "$d"
  mkdir -p "$d"
  local cfg="$root/config/sim.ini" gt="$s/groundtruth.txt"
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/single" > /dev/null
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/first" --first-frame "$mapFrom" \
    --max-frames "$mapFrames" --map "$d/session.kgmap" > /dev/null
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/extend" --first-frame "$from" \
    --max-frames "$frames" --load-map "$d/session.kgmap" > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/single/keyframes.txt" --json "$d/single_kf.json" > /dev/null
  # Both runs may hold keyframes of the same frames (office: 1650-1899): one per timestamp,
  # the stored map's (listed first), since keygrid-eval refuses repeated timestamps.
  awk '/^#/ || !seen[$1]++' "$d/extend/keyframes.txt" > "$d/merged_keyframes.txt"
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/merged_keyframes.txt" --json "$d/merged_kf.json" > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/extend/trajectory.txt" --map-run-gt "$gt" \
    --map-run-est "$d/first/trajectory.txt" --json "$d/extend_map_frame.json" > /dev/null
  /usr/bin/python3 - "$name" "$d" "$mapFrom" "$mapFrames" "$from" "$frames" <<'PY'
import json, sys
name, d = sys.argv[1], sys.argv[2]
m0, mn, x0, xn = (int(a) for a in sys.argv[3:7])
ext = json.load(open(f"{d}/extend/report.json"))
single, merged, second = (json.load(open(f"{d}/{f}.json")) for f in ("single_kf", "merged_kf", "extend_map_frame"))
s = ext["session"]
merges = [l["frame"] for l in ext["loop_closures"]]
ratio = merged["ate_rmse_m"] / single["ate_rmse_m"]
last = "end" if xn == 0 else x0 + xn - 1
print(f"{name:8} | map {m0}-{m0 + mn - 1}, extend {x0}-{last} | started {s['started']}, merged {s['maps_merged']}"
      f" (loops at frames {merges}) | merged keyframes ATE {1e3 * merged['ate_rmse_m']:.2f} mm vs single run"
      f" {1e3 * single['ate_rmse_m']:.2f} mm ({ratio:.2f}x) | second run in the first run's frame"
      f" {1e3 * second['ate_rmse_m']:.2f} mm ({second['matched']} frames) | waiting for merge {s['keyframes_waiting_for_merge']}")
PY
}

for c in $cases; do
  case "$c" in
    corridor) run_case corridor corridor_loop 0 450 600 0 ;;
    room) run_case room room_loop 0 150 250 0 ;;
    office) run_case office office_loop 1650 1650 400 1500 ;;
    *) die "unknown case '$c' (corridor, room, office)" ;;
  esac
done

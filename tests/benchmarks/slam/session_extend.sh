#!/usr/bin/env bash
# Map sessions, extend mode: map the first part of a keygrid-sim loop with keygrid-slam --map,
# then run a second part that starts where the stored map has never looked with
# --load-map FILE (no --localize): it maps on in a frame of its own and is merged into the
# stored map when loop closing finds a place both know. Compared, in the same run, with one
# keygrid-slam run over the whole sequence. Cases (keygrid-sim scenes, 2 m texture tiles):
#   corridor  config/sim/corridor_loop.ini: map frames 0-449, extend from frame 600 (1020)
#   room      config/sim/room_loop.ini: map frames 0-149, extend from frame 250 (450)
#   office    config/sim/office_loop.ini: map frames 0-1649, extend from frame 2000 (3300)
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
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
build="$root/build"
out=""
sim=""
cases="corridor room office"
usage() { sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --sim) sim="$2"; shift 2 ;;
    --cases) cases="$2"; shift 2 ;;
    --help|-h) usage; exit 0 ;;
    *) echo "session_extend.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$out" ] || out="$(mktemp -d)"
[ -n "$sim" ] || sim="$out/sim"
mkdir -p "$out" "$sim"
bin="$build/bin"
for t in keygrid-sim keygrid-slam keygrid-eval; do
  [ -x "$bin/$t" ] || { echo "session_extend.sh: $bin/$t not found (build it, or pass --build)" >&2; exit 2; }
done

# run_case NAME SCENE MAP_FRAMES EXTEND_FROM
run_case() {
  local name="$1" scene="$2" mapFrames="$3" from="$4"
  local s="$sim/$scene" d="$out/$name"
  [ -f "$s/groundtruth.txt" ] || "$bin/keygrid-sim" --quiet --scene "$root/config/sim/$scene.ini" --output "$s" \
    --voxel-resolution 0 --floorplan-resolution 0
  rm -rf "$d"
  mkdir -p "$d"
  local cfg="$root/config/sim.ini" gt="$s/groundtruth.txt"
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/single" > /dev/null
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/first" --max-frames "$mapFrames" \
    --map "$d/session.kgmap" > /dev/null
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$s/tum" --output "$d/extend" --first-frame "$from" \
    --load-map "$d/session.kgmap" > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/single/keyframes.txt" --json "$d/single_kf.json" > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/extend/keyframes.txt" --json "$d/merged_kf.json" > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$gt" --est "$d/extend/trajectory.txt" --map-run-gt "$gt" \
    --map-run-est "$d/first/trajectory.txt" --json "$d/extend_map_frame.json" > /dev/null
  /usr/bin/python3 - "$name" "$d" "$mapFrames" "$from" <<'PY'
import json, sys
name, d, n, start = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
ext = json.load(open(f"{d}/extend/report.json"))
single, merged, second = (json.load(open(f"{d}/{f}.json")) for f in ("single_kf", "merged_kf", "extend_map_frame"))
s = ext["session"]
merges = [l["frame"] for l in ext["loop_closures"]]
ratio = merged["ate_rmse_m"] / single["ate_rmse_m"]
print(f"{name:8} | map 0-{n - 1}, extend from {start} | started {s['started']}, merged {s['maps_merged']}"
      f" (loops at frames {merges}) | merged keyframes ATE {1e3 * merged['ate_rmse_m']:.2f} mm vs single run"
      f" {1e3 * single['ate_rmse_m']:.2f} mm ({ratio:.2f}x) | second run in the first run's frame"
      f" {1e3 * second['ate_rmse_m']:.2f} mm ({second['matched']} frames) | waiting for merge {s['keyframes_waiting_for_merge']}")
PY
}

for c in $cases; do
  case "$c" in
    corridor) run_case corridor corridor_loop 450 600 ;;
    room) run_case room room_loop 150 250 ;;
    office) run_case office office_loop 1650 2000 ;;
    *) echo "session_extend.sh: unknown case '$c' (corridor, room, office)" >&2; exit 2 ;;
  esac
done

#!/usr/bin/env bash
# Floor-frame benchmark: keygrid-slam's estimated T_world_floor against the true
# floor of every shipped synthetic scene with a floor plan. The sim world is z-up with the
# floor at z = 0; the SLAM world is carried into it by the SE(3) Umeyama alignment of
# trajectory.txt to groundtruth.txt, and each accepted estimate of report.json's "floor"
# history is scored: height offset (the plane's z under the trajectory's centroid) and tilt
# (angle of its normal to +z). One line per scene: after 10 keyframes, worst from 10 keyframes
# on, and at the end.
#   tests/benchmarks/maps_ism/floor_estimate_sim.sh [BUILD_DIR] [OUT_DIR] [CONFIG]
# Needs the targets keygrid-sim keygrid-slam keygrid_floor_estimate_eval
# (KEYGRID_BUILD_BENCHMARKS=ON). Results: doc/evaluation.md, "Floor frame".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
build="$(kg_build_dir "${1:-$build}" keygrid-sim keygrid-slam keygrid_floor_estimate_eval)" || exit 2
out="${2:-$(mktemp -d)}"
cfg="$(realpath "${3:-$root/config/sim.ini}")"
mkdir -p "$out"
# scene:frame limit (0 = the scene's own length); office_loop (3300 frames, 44 m) is cut to
# its first 1200 frames to keep the run short.
for entry in room_loop:0 room_survey:0 corridor_loop:0 office_loop:1200 relocalization:0; do
  scene="${entry%%:*}"; frames="${entry##*:}"
  sim="$out/$scene"
  limit=(); [ "$frames" != 0 ] && limit=(--frames "$frames")
  [ -f "$sim/groundtruth.txt" ] || "$build/bin/keygrid-sim" --quiet --scene "$root/config/sim/$scene.ini" \
    --output "$sim" --voxel-resolution 0 --floorplan-resolution 0 "${limit[@]}"
  [ -f "$sim/slam/report.json" ] || "$build/bin/keygrid-slam" --quiet --config "$cfg" \
    --input "$sim/tum" --output "$sim/slam" --gt "$sim/groundtruth.txt" > /dev/null
  "$build/bin/keygrid_floor_estimate_eval" --name "$scene" --gt "$sim/groundtruth.txt" \
    --traj "$sim/slam/trajectory.txt" --report "$sim/slam/report.json"
done

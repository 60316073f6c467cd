#!/usr/bin/env bash
# Accuracy benchmark: CISMOccupancyGrid2D against keygrid-sim's floor plan (5 cm cells)
# on a room scene (default config/sim/room_survey.ini; also run it with room_loop.ini), with
# ground-truth poses and with keygrid-slam's poses, sparse (ORB keypoints + depth) and dense
# input, and keygrid-slam's own map_2d (config/sim.ini, i.e. sparse map points and RANSAC floor;
# and the same config with ism2d_input = dense).
#   tests/benchmarks/maps_ism/ism2d_sim_f1.sh [BUILD_DIR] [OUT_DIR] [EVERY] [SCENE_INI]
# Needs the targets keygrid-sim keygrid-slam keygrid_ism2d_sim_eval (KEYGRID_BUILD_BENCHMARKS=ON).
# Results and their discussion: doc/maps-ism2d.md.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
build="$(kg_build_dir "${1:-$build}" keygrid-sim keygrid-slam keygrid_ism2d_sim_eval)" || exit 2
out="${2:-$(mktemp -d)}"
every="${3:-10}"
scene="$(realpath "${4:-$root/config/sim/room_survey.ini}")"
eval="$build/bin/keygrid_ism2d_sim_eval"
mkdir -p "$out"
[ -f "$out/room/floorplan.yaml" ] || "$build/bin/keygrid-sim" --scene "$scene" --output "$out/room"
sed 's/^ism2d_input = sparse/ism2d_input = dense/' "$root/config/sim.ini" > "$out/sim_dense.ini"
for input in sparse dense; do
  cfg="$root/config/sim.ini"; [ "$input" = dense ] && cfg="$out/sim_dense.ini"
  [ -f "$out/slam_$input/trajectory.txt" ] || "$build/bin/keygrid-slam" --quiet --config "$cfg" \
    --input "$out/room/tum" --output "$out/slam_$input" --gt "$out/room/groundtruth.txt"
done
echo "== ground-truth poses, every $every-th frame a keyframe"
"$eval" --sim "$out/room" --every "$every" --scene "$scene"
echo "== keygrid-slam poses (config/sim.ini run), aligned to the sim world (Umeyama), known floor"
"$eval" --sim "$out/room" --every "$every" --poses "$out/slam_sparse/trajectory.txt" --align umeyama
for input in sparse dense; do
  echo "== keygrid-slam's own map_2d, ism2d_input = $input (floor from RANSAC)"
  "$eval" --sim "$out/room" --poses "$out/slam_$input/trajectory.txt" --align umeyama \
    --slam-map "$out/slam_$input/map_2d.yaml"
done

#!/usr/bin/env bash
# `make demo`: the main job on data the project makes itself.
#   1. keygrid-sim renders config/sim/room_loop.ini (a furnished room, the camera circles it and
#      returns to its start; Kinect-like noise; exact ground truth);
#   2. keygrid-slam runs config/sim.ini on the rendered rawlog: trajectory, keyframes, the 2D ISM
#      navigation grid and the submapped 3D occupancy grid;
#   3. keygrid-eval scores the trajectory against the ground truth.
set -euo pipefail
build="${1:-build}"
bin="$build/bin"
out="${KEYGRID_DEMO_OUT:-out/demo}"
mkdir -p "$out"
start=$(date +%s)

echo "== 1/3 keygrid-sim: config/sim/room_loop.ini -> $out/sim"
"$bin/keygrid-sim" --scene config/sim/room_loop.ini --output "$out/sim"

echo "== 2/3 keygrid-slam: config/sim.ini on $out/sim/sequence.rawlog -> $out/slam"
"$bin/keygrid-slam" --config config/sim.ini --input "$out/sim/sequence.rawlog" \
  --output "$out/slam" --gt "$out/sim/groundtruth.txt"

echo "== 3/3 keygrid-eval"
"$bin/keygrid-eval" --gt "$out/sim/groundtruth.txt" --est "$out/slam/trajectory.txt" --json "$out/slam/eval.json"

python3 - "$out/slam/report.json" "$(( $(date +%s) - start ))" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print()
print(f"keygrid demo finished in {sys.argv[2]} s")
print(f"  frames {r['frames']}, tracked {r['tracked']}, {r['fps']:.1f} fps, keyframes {r['keyframes']}, landmarks {r['landmarks']}")
if 'ate_rmse_m' in r: print(f"  ATE RMSE {100*r['ate_rmse_m']:.2f} cm against the simulator's ground truth")
print(f"  loop closures: {len(r.get('loop_closures', []))}")
for m in r.get('maps', []): print("  map", m)
PY
echo
echo "Outputs:"
echo "  $out/sim/                 rendered sequence (sequence.rawlog, tum/, groundtruth.txt, floorplan.pgm)"
echo "  $out/slam/trajectory.txt  estimated trajectory (TUM format); report.json, frames.csv"
echo "  $out/slam/map_2d.png      2D navigation grid (also map_2d.pgm + map_2d.yaml for map_server)"
echo "  $out/slam/map_3d.bt       3D occupancy grid (octovis $out/slam/map_3d.bt); map_3d.ply"
echo "  $out/slam/hoc_points.ply  landmarks coloured by their HOC weight; *.bin = the maps serialized"
echo "  $out/slam/scene.3Dscene   everything for SceneViewer3D -l build/libs/maps/libkeygrid_maps.so"
echo "  $out/slam/keyframes.simplemap  keyframe poses + observations for MRPT's observations2map"
echo "  RawLogViewer $out/sim/sequence.rawlog   to browse the input"

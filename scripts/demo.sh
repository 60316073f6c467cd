#!/usr/bin/env bash
# `make demo`: the main job on data the project makes itself.
#   1. keygrid-sim renders config/sim/room_loop.ini (a furnished room, the camera circles it and
#      returns to its start; Kinect-like noise; exact ground truth);
#   2. keygrid-slam runs config/sim.ini on the rendered rawlog: trajectory, keyframes, the 2D ISM
#      navigation grid and the submapped 3D occupancy grid;
#   3. keygrid-eval scores the trajectory against the ground truth and the 2D grid against the
#      simulator's floor plan (hazard cells = obstacles called free, obstacle recall over the
#      boundary the cameras saw, precision, free-space F1), and draws the grid over the plan in
#      $out/map_overlay.png (colours: doc/maps-ism2d.md).
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

echo "== 3/3 keygrid-eval: trajectory and 2D map against the ground truth -> $out/map_overlay.png"
"$bin/keygrid-eval" --gt "$out/sim/groundtruth.txt" --est "$out/slam/trajectory.txt" --json "$out/slam/eval.json" \
  --map "$out/slam/map_2d.yaml" --floorplan "$out/sim/floorplan.yaml" \
  --scene config/sim/room_loop.ini --keyframes "$out/slam/keyframes.txt" --overlay "$out/map_overlay.png"

python3 - "$out/slam/report.json" "$(( $(date +%s) - start ))" "$out/slam/eval.json" "$out/map_overlay.png" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
e = json.load(open(sys.argv[3]))
print()
print(f"keygrid demo finished in {sys.argv[2]} s")
print(f"  frames {r['frames']}, tracked {r['tracked']}, {r['fps']:.1f} fps, keyframes {r['keyframes']}, landmarks {r['landmarks']}")
if 'ate_rmse_m' in r: print(f"  ATE RMSE {100*r['ate_rmse_m']:.2f} cm against the simulator's ground truth")
print(f"  loop closures: {len(r.get('loop_closures', []))}")
for m in r.get('maps', []): print("  map", m)
print(f"  2D map vs the floor plan: hazard cells {e['map_hazard_cells']} (obstacle cells called free, "
      f"of {e['map_interior_obstacle_cells']} interior), obstacle recall {e['map_boundary_recall']:.3f} "
      f"(boundary cells seen), precision {e['map_obstacle_precision']:.3f}, free-space F1 "
      f"{e['map_free_f1_floor_seen']:.3f} where the floor was in view ({e['map_free_f1']:.3f} where any ray passed); "
      f"floor {100*e['map_floor_offset_m']:+.1f} cm / {e['map_floor_tilt_deg']:.2f} deg off")
print(f"  overlay: {sys.argv[4]}  (black occupied, white free, orange missed, red HAZARD, blue false obstacle)")
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
echo "  $out/map_overlay.png      the 2D grid over the simulator's floor plan (legend in the image)"

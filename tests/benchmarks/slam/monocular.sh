#!/usr/bin/env bash
# Monocular mode ([slam] sensor = monocular): keygrid-slam on images alone, per case without and
# with the camera's height above the floor ([camera_height_scale] camera_height). Cases:
#   room    config/sim/room_loop.ini rendered as a plain camera (camera at 1.30 m)
#   office  config/sim/office_loop.ini rendered the same way (camera at 1.40 m; 3300 frames)
#   corridor config/sim/corridor_loop.ini (1.40 m, 1020 frames), survey config/sim/room_survey.ini
#           (1.30 m, 1950 frames): validation scenes, run with the height only (not in the defaults)
#   fr1     ../shared/data/tum_fr1_rpy_first250 with its depth ignored (no height: hand-held)
#   desk    ../shared/data/tum_fr1_desk_9frames with its depth ignored
# Prints per run: the frame the map started at, frames tracked after it, the ATE of the tracked
# frames after Sim(3) alignment and as a share of the ground-truth path they cover, the ATE after SE(3) alignment
# (with a height: the map is metric), the scale error (Sim(3) alignment scale - 1) and the
# frame rate. With a height, on the rendered scenes, the 2D grid (map_2d.yaml, the keyframes' map
# points on the camera-height floor) is scored against the scene's floor plan by keygrid-eval's
# map mode, the scorer of the RGB-D grids (tests/benchmarks/maps_ism/nav_safety_sim.sh): hazard
# cells (interior obstacle cells called free), every obstacle cell called free, obstacle recall
# over the boundary cells seen and obstacle precision; the hazard cells also after a Sim(3)
# alignment (the grid's cells scaled with it: what is left without the scale error). Without a height the grid is in the map's
# arbitrary unit and is not scored. On the rendered scenes the 3D grid (map_3d.bt) is scored
# against the scene's true voxels (occupancy_voxels.txt) by keygrid-eval's 3D grid mode, after
# SE(3) alignment with a height, Sim(3) without: occupied voxels, precision, recall over the true
# voxels the keyframes saw within 4 m, hazard voxels (true voxels called free, no map voxel near).
# Renderings are made once per --out folder; the TUM cases are skipped when their data is absent.
#
#   tests/benchmarks/slam/monocular.sh [--build DIR] [--out DIR] [--cases "room office fr1 desk"]
#       [--set "KEY=VALUE; ..."] [--help]
#   (also: --cases "corridor survey"; --set adds keygrid-slam overrides to every run, e.g.
#   --set slam.mode=threaded)
# Results: doc/evaluation.md, "Monocular mode".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
out=/tmp/keygrid_monocular
cases="room office fr1 desk"
extra=""
data="$root/../shared/data"
kg_parse_args --build=build --out=out --cases=cases --set=extra -- "$@"
build="$(kg_build_dir "$build" keygrid-sim keygrid-slam keygrid-eval)" || exit 2
mkdir -p "$out" || die "cannot create $out"

# render NAME SCENE -> $out/sim/NAME (once)
render() {
  local dir="$out/sim/$1"
  if [ ! -f "$dir/groundtruth.txt" ]; then
    echo "== rendering $1 as a plain camera -> $dir" >&2
    rm -rf "$dir"
    "$build/bin/keygrid-sim" --quiet --scene "$root/config/sim/$2.ini" --output "$dir" \
      --set 'output.sensor=monocular' >"$out/render_$1.log" 2>&1 || die "keygrid-sim failed: $out/render_$1.log"
  fi
  echo "$dir"
}

# run TAG CONFIG INPUT GT HEIGHT [SCENE [SET]]: one keygrid-slam run and its table row; SCENE (a
# config/sim scene rendered into the folder of GT) has its 3D grid scored, its 2D grid when HEIGHT
# is given
run() {
  local tag="$1" cfg="$2" input="$3" gt="$4" height="$5" scene="${6:-}" set="${7:-}"
  local dir="$out/run_$tag"
  rm -rf "$dir"; mkdir -p "$dir"
  local overrides="slam.sensor=monocular"
  [ "$height" != 0 ] && overrides="$overrides; camera_height_scale.camera_height=$height"
  [ -n "$set" ] && overrides="$overrides; $set"
  [ -n "$extra" ] && overrides="$overrides; $extra"
  echo "== $tag: keygrid-slam -> $dir" >&2
  "$build/bin/keygrid-slam" --quiet --config "$cfg" --input "$input" --gt "$gt" --output "$dir" \
    --set "$overrides" >"$dir/slam.log" 2>&1 || { echo "| $tag | keygrid-slam failed: $dir/slam.log |"; return; }
  # The poses of tracked frames only (frames.csv): a lost frame's pose is a guess.
  /usr/bin/python3 - "$dir/frames.csv" "$dir/trajectory.txt" "$dir/trajectory_tracked.txt" <<'PY'
import csv, os, sys
frames, traj, out = sys.argv[1:4]
tracked = set()
if os.path.exists(frames):
    for row in csv.DictReader(open(frames)):
        if row["tracked"] == "1": tracked.add(round(float(row["timestamp"]), 4))
with open(out, "w") as f:
    for line in (open(traj) if os.path.exists(traj) else []):
        if line.startswith("#") or round(float(line.split()[0]), 4) in tracked: f.write(line)
PY
  local sim3="" se3=""
  if grep -qv '^#' "$dir/trajectory_tracked.txt"; then
    sim3="$("$build/bin/keygrid-eval" --gt "$gt" --est "$dir/trajectory_tracked.txt" --sim3 2>/dev/null || true)"
    se3="$("$build/bin/keygrid-eval" --gt "$gt" --est "$dir/trajectory_tracked.txt" 2>/dev/null || true)"
  fi
  local grid="$dir/eval_map.json"
  if [ -n "$scene" ] && [ "$height" != 0 ] && [ -f "$dir/map_2d.yaml" ]; then
    "$build/bin/keygrid-eval" --quiet --gt "$gt" --est "$dir/trajectory.txt" --map "$dir/map_2d.yaml" \
      --floorplan "$(dirname "$gt")/floorplan.yaml" --scene "$root/config/sim/$scene.ini" \
      --keyframes "$dir/keyframes.txt" --overlay "$dir/overlay.png" --json "$grid" >"$dir/eval_map.txt" 2>&1 \
      || echo "monocular.sh: grid scoring failed: $dir/eval_map.txt" >&2
    # The same grid after a Sim(3) alignment: what is left once the scale error is taken out.
    "$build/bin/keygrid-eval" --quiet --gt "$gt" --est "$dir/trajectory.txt" --sim3 --map "$dir/map_2d.yaml" \
      --floorplan "$(dirname "$gt")/floorplan.yaml" --json "$dir/eval_map_sim3.json" >"$dir/eval_map_sim3.txt" 2>&1 \
      || echo "monocular.sh: grid scoring (Sim(3)) failed: $dir/eval_map_sim3.txt" >&2
  fi
  local grid3d="$dir/eval_grid3d.json"
  if [ -n "$scene" ] && [ -f "$dir/map_3d.bt" ]; then
    local align=""
    [ "$height" = 0 ] && align="--sim3"
    "$build/bin/keygrid-eval" --quiet --gt "$gt" --est "$dir/trajectory.txt" $align --grid3d "$dir/map_3d.bt" \
      --voxels "$(dirname "$gt")/occupancy_voxels.txt" --scene "$root/config/sim/$scene.ini" \
      --keyframes "$dir/keyframes.txt" --json "$grid3d" >"$dir/eval_grid3d.txt" 2>&1 \
      || echo "monocular.sh: 3D grid scoring failed: $dir/eval_grid3d.txt" >&2
  fi
  /usr/bin/python3 - "$dir/report.json" "$gt" "$tag" "$height" "$sim3" "$se3" "$dir/trajectory_tracked.txt" "$grid" "$grid3d" <<'PY'
import json, math, os, re, sys
report, gt, tag, height, sim3, se3, traj, grid, grid3d = sys.argv[1:10]
r = json.load(open(report))
def rows(path):
    if not os.path.exists(path): return []
    return [list(map(float, l.split()[:4])) for l in open(path) if l.strip() and not l.startswith("#")]
# Path length of the ground truth over the time the tracked poses cover.
est = rows(traj)
t0, t1 = (est[0][0], est[-1][0]) if est else (0.0, -1.0)
pts = [g[1:4] for g in rows(gt) if t0 - 0.02 <= g[0] <= t1 + 0.02]
path = sum(math.dist(a, b) for a, b in zip(pts, pts[1:])) or float("nan")
def ate(text):
    m = re.search(r"ATE rmse ([0-9.eE+-]+) m", text)
    return float(m.group(1)) if m else float("nan")
init = r.get("initialization", {})
start = init.get("frame")
tracked_after = r["tracked"] if start is not None else 0
after = r["frames"] - start if start is not None else 0
m = re.search(r"Sim\(3\) alignment scale ([0-9.eE+-]+)", sim3)
scale = float(m.group(1)) if m else float("nan")
a_sim3, a_se3 = ate(sim3), ate(se3)
scale_err = f"{100 * abs(scale - 1):.2f} %" if height != "0" and scale == scale else "-"
se3_text = f"{1000 * a_se3:.1f} mm = {100 * a_se3 / path:.2f} %" if height != "0" and a_se3 == a_se3 else "-"
sim3_text = f"{1000 * a_sim3:.1f} mm = {100 * a_sim3 / path:.2f} %" if a_sim3 == a_sim3 else "-"
grid_text = "- | - | - | -"
if os.path.exists(grid):
    e = json.load(open(grid))
    sim3_grid = os.path.join(os.path.dirname(grid), "eval_map_sim3.json")
    after_sim3 = f" ({json.load(open(sim3_grid))['map_hazard_cells']} after Sim(3))" if os.path.exists(sim3_grid) else ""
    grid_text = (f"{e['map_hazard_cells']} of {e['map_interior_obstacle_cells']}{after_sim3} | {e['map_obstacle_called_free_cells']} "
                 f"| {e['map_boundary_recall']:.3f} ({e['map_boundary_cells_seen']} seen) | {e['map_obstacle_precision']:.3f}")
grid3d_text = "- | - | - | -"
if os.path.exists(grid3d):
    e = json.load(open(grid3d))
    grid3d_text = (f"{e['grid3d_occupied_voxels']} | {e['grid3d_precision']:.3f} "
                   f"| {e['grid3d_recall_seen']:.3f} ({e['grid3d_true_voxels_seen']} seen) | {e['grid3d_hazard_voxels']}")
print(f"| {tag} | {height if height != '0' else '-'} | {start if start is not None else 'never'} "
      f"| {tracked_after} / {after} | {sim3_text} | {se3_text} | {scale_err} | {r.get('fps', 0):.1f} | {path:.2f} m "
      f"| {grid_text} | {grid3d_text} |")
PY
}

echo "| run | camera_height [m] | map start (frame) | tracked after it | ATE, Sim(3) (share of the path) | ATE, SE(3) | scale error | fps | ground-truth path | 2D grid: hazard cells (interior) | obstacle cells called free | obstacle recall, seen boundary | obstacle precision | 3D grid: occupied voxels | voxel precision | voxel recall, seen | hazard voxels |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
mono="$root/config/sim_monocular.ini"
for c in $cases; do
  case "$c" in
    room)
      d="$(render room_loop room_loop)"
      run room_loop "$mono" "$d/tum" "$d/groundtruth.txt" 0 room_loop
      run room_loop_h "$mono" "$d/tum" "$d/groundtruth.txt" 1.30 room_loop ;;
    office)
      d="$(render office_loop office_loop)"
      run office_loop "$mono" "$d/tum" "$d/groundtruth.txt" 0 office_loop
      run office_loop_h "$mono" "$d/tum" "$d/groundtruth.txt" 1.40 office_loop ;;
    corridor|survey)
      # Validation scenes (not tuned on): with camera_height only (threaded: --set slam.mode=threaded).
      scene=corridor_loop; h=1.40; [ "$c" = survey ] && scene=room_survey h=1.30
      d="$(render $scene $scene)"
      run "${scene}_h" "$mono" "$d/tum" "$d/groundtruth.txt" $h $scene ;;
    fr1|desk)
      seq=tum_fr1_rpy_first250; [ "$c" = desk ] && seq=tum_fr1_desk_9frames
      if [ -f "$data/$seq/groundtruth.txt" ]; then
        run "$seq" "$root/config/tum_fr1.ini" "$data/$seq" "$data/$seq/groundtruth.txt" 0
      else
        echo "monocular.sh: $data/$seq not found: case $c skipped" >&2
      fi ;;
    *) die "unknown case '$c' (room office corridor survey fr1 desk)" ;;
  esac
done

#!/usr/bin/env bash
# Benchmark: how navigation-safe keygrid-slam's own 2D map is on every shipped synthetic
# scene with a floor plan. For each scene: render it with keygrid-sim (cached), run keygrid-slam
# with config/sim.ini (its own poses, floor estimated) for every free-space model x 2D input, and
# score map_2d against the floor plan with keygrid-eval's map mode (visibility rendered at the
# keyframes' ground-truth poses). One table row per (scene, model, input):
#   hazard cells (interior obstacle cells called free; 0 = navigation-safe), obstacle recall over
#   the boundary cells the cameras saw, obstacle precision, free-space F1 (precision / recall over
#   the free cells in view, and recall over the free cells whose floor-level space was in view),
#   floor error of the estimate (height at its origin / tilt), ATE.
# Definitions: doc/maps-ism2d.md "Navigation safety". Uses shipped tools only.
#
#   tests/benchmarks/maps_ism/nav_safety_sim.sh [--build DIR] [--out DIR] [--scenes "room_loop ..."]
#       [--models "heightBand paper"] [--inputs "sparse dense"] [--max-frames N] [--sim-frames N]
#       [--set 'SECTION.KEY=V; ...'] [--tag NAME]
#
#   --build DIR        build tree with bin/keygrid-sim, keygrid-slam, keygrid-eval (default: build)
#   --out DIR          renders (kept and reused) and runs (redone every time) (default:
#                      /tmp/keygrid_nav_safety)
#   --scenes LIST      names under config/sim/ (default: room_loop room_survey corridor_loop
#                      office_loop relocalization; office_loop is 3300 frames)
#   --models LIST      values of the 2D grid's freeSpaceModel (default: heightBand paper)
#   --inputs LIST      values of [maps] ism2d_input (default: sparse dense)
#   --max-frames N     keygrid-slam stops after N frames (the render stays complete) (default: all)
#   --sim-frames N     render N frames instead of the scene's count: keygrid-sim --frames, the same
#                      walk stretched to N frames, i.e. a faster camera (default: the scene's)
#   --set OVERRIDES    more keygrid-slam --set overrides for every run (default: none)
#   --tag NAME         suffix of the run folders, to keep runs with other --set apart (default: none)
#
# The model is passed as --set 'MappingApplication_ismOccupancyGrid2D_00_insertOpts.freeSpaceModel=M'.
# A keygrid-slam that does not know the key (before the height-band grid) rejects it; the script then
# runs "paper" without the key (that grid IS the paper's model) and reports the other models n/a.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
out=/tmp/keygrid_nav_safety
scenes="room_loop room_survey corridor_loop office_loop relocalization"
models="heightBand paper"
inputs="sparse dense"
maxFrames=0
simFrames=0
extraSet=""
runTag=""
kg_parse_args --build=build --out=out --scenes=scenes --models=models --inputs=inputs --max-frames=maxFrames \
  --sim-frames=simFrames --set=extraSet --tag=runTag -- "$@"
[ -z "$runTag" ] || runTag="_$runTag"
kg_whole_number --max-frames "$maxFrames"
kg_whole_number --sim-frames "$simFrames"
for m in $models; do [ "$m" = heightBand ] || [ "$m" = paper ] || die "--models: unknown model '$m' (heightBand | paper)"; done
for i in $inputs; do [ "$i" = sparse ] || [ "$i" = dense ] || die "--inputs: unknown input '$i' (sparse | dense)"; done
build="$(kg_build_dir "$build" keygrid-sim keygrid-slam keygrid-eval)" || exit 2
bin="$build/bin"
for s in $scenes; do [ -f "$root/config/sim/$s.ini" ] || die "--scenes: no scene config/sim/$s.ini"; done
mkdir -p "$out"

section=MappingApplication_ismOccupancyGrid2D_00_insertOpts
# (the reference is read whole first: grep -q would close the pipe early, and pipefail would see
# keygrid-slam's SIGPIPE)
if grep -q freeSpaceModel <<< "$("$bin/keygrid-slam" --ini-reference)"; then haveModel=1; else
  haveModel=0
  echo "note: this keygrid-slam has no $section.freeSpaceModel: 'paper' runs without the key (today's grid), other models n/a"
fi

# Renders are cached per scene and frame count, keyed by the scene file's content.
render() {
  local scene="$1" dir="$2" ini="$root/config/sim/$1.ini" sum
  sum="$(sha1sum "$ini" | cut -c1-40) frames=$simFrames"
  if [ -f "$dir/.complete" ] && [ "$(cat "$dir/.complete")" = "$sum" ]; then return 0; fi
  rm -rf "$dir"
  local extra=(); [ "$simFrames" -gt 0 ] && extra=(--frames "$simFrames")
  echo "== rendering $scene -> $dir" >&2
  "$bin/keygrid-sim" --quiet --scene "$ini" --output "$dir" "${extra[@]}" >"$out/render_$scene.log" 2>&1 \
    || { echo "keygrid-sim failed on $scene: $out/render_$scene.log" >&2; return 1; }
  echo "$sum" > "$dir/.complete"
}

row() { printf '| %-14s | %-10s | %-6s | %11s | %-6s | %-12s | %-15s | %-23s | %-14s | %-18s | %8s |\n' "$@"; }
table=$(mktemp)
{
  row scene model input "hazard" "of" "obst. recall" "obst. precision" "free F1 (P / R)" "floor seen: F1 / R" "floor dz / tilt" "ATE"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
} > "$table"

tag=""; [ "$simFrames" -gt 0 ] && tag="_f$simFrames"
for scene in $scenes; do
  sim="$out/sim/$scene$tag"
  if ! render "$scene" "$sim"; then row "$scene" - - "render failed" "" "" "" "" "" "" >> "$table"; continue; fi
  for model in $models; do
    for input in $inputs; do
      run="$out/run/$scene${tag}_${model}_${input}${runTag}"; [ "$maxFrames" -gt 0 ] && run="${run}_m$maxFrames"
      overrides="maps.ism2d_input=$input"
      [ -n "$extraSet" ] && overrides="$overrides; $extraSet"
      if [ "$haveModel" = 1 ]; then overrides="$overrides; $section.freeSpaceModel=$model"
      elif [ "$model" != paper ]; then row "$scene" "$model" "$input" "n/a" "" "" "" "(no freeSpaceModel key)" "" "" >> "$table"; continue
      fi
      rm -rf "$run"; mkdir -p "$run"
      extra=(); [ "$maxFrames" -gt 0 ] && extra=(--max-frames "$maxFrames")
      echo "== $scene, $model, $input: keygrid-slam -> $run" >&2
      # Scenes with [output] write_rawlog = false (office_loop) have only the TUM folder.
      input_path="$sim/sequence.rawlog"; [ -f "$input_path" ] || input_path="$sim/tum"
      if ! "$bin/keygrid-slam" --quiet --config "$root/config/sim.ini" --input "$input_path" \
          --output "$run" --gt "$sim/groundtruth.txt" --set "$overrides" "${extra[@]}" >"$run/slam.log" 2>&1; then
        row "$scene" "$model" "$input" "slam failed" "" "" "" "$run/slam.log" "" "" >> "$table"; continue
      fi
      if ! "$bin/keygrid-eval" --quiet --gt "$sim/groundtruth.txt" --est "$run/trajectory.txt" \
          --map "$run/map_2d.yaml" --floorplan "$sim/floorplan.yaml" --scene "$root/config/sim/$scene.ini" \
          --keyframes "$run/keyframes.txt" --overlay "$run/overlay.png" --json "$run/eval.json" >"$run/eval.txt" 2>&1; then
        row "$scene" "$model" "$input" "eval failed" "" "" "" "$run/eval.txt" "" "" >> "$table"; continue
      fi
      IFS=$'\t' read -r -a f < <(python3 - "$run/eval.json" <<'PY'
import json, sys
e = json.load(open(sys.argv[1]))
print("\t".join([str(e["map_hazard_cells"]), str(e["map_interior_obstacle_cells"]),
    f"{e['map_boundary_recall']:.3f}", f"{e['map_obstacle_precision']:.3f}",
    f"{e['map_free_f1']:.3f} ({e['map_free_precision']:.3f} / {e['map_free_recall']:.3f})",
    f"{e['map_free_f1_floor_seen']:.3f} / {e['map_free_recall_floor_seen']:.3f}",
    f"{100 * e['map_floor_offset_m']:+.1f} cm / {e['map_floor_tilt_deg']:.2f} deg", f"{100 * e['ate_rmse_m']:.2f} cm"]))
PY
)
      row "$scene" "$model" "$input" "${f[@]}" >> "$table"
    done
  done
done
echo
echo "keygrid-slam config/sim.ini, map_2d vs floorplan (5 cm cells, 1-cell tolerance); hazard = interior"
echo "obstacle cells called free; recall over the obstacle boundary cells seen from the keyframes;"
echo "free F1 over the free cells in view, and over those whose floor-level space was in view;"
echo "floor = estimated floor in the ground-truth world."
echo "Overlays: $out/run/<scene>_<model>_<input>$runTag/overlay.png"
cat "$table"
rm -f "$table"

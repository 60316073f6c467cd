#!/usr/bin/env bash
# Map sessions: map once with keygrid-slam --map, then localize another sequence in the stored
# map (--load-map FILE --localize) and measure it in the map's frame, without aligning the
# second run: the map frame is fixed by the mapping run's poses against its ground truth
# (keygrid-eval --map-run-gt/--map-run-est). Two cases:
#   sim  map config/sim/room_loop.ini (450 frames), localize config/sim/room_loop_revisit.ini
#        (300 frames: a second path through the same room, starting 22.5 deg off);
#   fr1  map frames 0-149 of ../shared/data/tum_fr1_rpy_first250, localize frames 150-249.
# Prints per case: frames localized, ATE in the map frame, the mapping run's ATE and fps with
# and without recording, recording cost per keyframe, file size per keyframe, load time.
#
#   tests/benchmarks/slam/session_localize.sh [--build DIR] [--out DIR] [--cases "sim fr1"] [--help]
# Results: doc/evaluation.md, "Map sessions".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
out=""
cases="sim fr1"
data="$root/../shared/data"
kg_parse_args --build=build --out=out --cases=cases -- "$@"
build="$(kg_build_dir "$build" keygrid-sim keygrid-slam keygrid-eval keygrid-map)" || exit 2
[ -n "$out" ] || out="$(mktemp -d)"
mkdir -p "$out"
bin="$build/bin"

# case NAME CONFIG MAP_INPUT MAP_GT MAP_ARGS LOC_INPUT LOC_GT LOC_ARGS
run_case() {
  local name="$1" cfg="$2" min="$3" mgt="$4" margs="$5" lin="$6" lgt="$7" largs="$8"
  local d="$out/$name"
  rm -rf "$d/plain" "$d/map" "$d/loc" "$d/session.kgmap"*
  mkdir -p "$d"
  # shellcheck disable=SC2086
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$min" --output "$d/plain" --gt "$mgt" $margs > /dev/null
  # shellcheck disable=SC2086
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$min" --output "$d/map" --gt "$mgt" $margs --map "$d/session.kgmap" > /dev/null
  # shellcheck disable=SC2086
  "$bin/keygrid-slam" --quiet --config "$cfg" --input "$lin" --output "$d/loc" --load-map "$d/session.kgmap" --localize $largs > /dev/null
  "$bin/keygrid-eval" --quiet --gt "$lgt" --est "$d/loc/trajectory.txt" --map-run-gt "$mgt" \
    --map-run-est "$d/map/trajectory.txt" --json "$d/loc/eval_map_frame.json" > /dev/null
  /usr/bin/python3 - "$name" "$d" <<'PY'
import json, sys
name, d = sys.argv[1], sys.argv[2]
plain, rec, loc = (json.load(open(f"{d}/{r}/report.json")) for r in ("plain", "map", "loc"))
ev = json.load(open(f"{d}/loc/eval_map_frame.json"))
s, l = rec["session"], loc["session"]
print(f"{name:4} | localized {l['localized']} of {loc['frames']} ({100 * l['localized_ratio']:.1f} %) | "
      f"ATE in the map frame {1e3 * ev['ate_rmse_m']:.2f} mm | mapping run ATE {1e3 * rec['ate_rmse_m']:.2f} mm "
      f"(plain {1e3 * plain['ate_rmse_m']:.2f}), {rec['fps']:.1f} fps (plain {plain['fps']:.1f}) | recording "
      f"{s['build_ms_per_update']:.2f} ms per keyframe on the mapping side, {1024 * s['file_mb'] / rec['keyframes']:.0f} KiB "
      f"per keyframe | load {l['load_s']:.3f} s ({l['keyframes']} keyframes, {l['landmarks']} landmarks)")
PY
  cmp -s "$d/plain/trajectory.txt" "$d/map/trajectory.txt" || echo "     note: recording changed the mapping run's trajectory"
}

for c in $cases; do
  case "$c" in
    sim)
      for scene in room_loop room_loop_revisit; do
        [ -f "$out/sim/$scene/groundtruth.txt" ] || "$bin/keygrid-sim" --quiet --scene "$root/config/sim/$scene.ini" \
          --output "$out/sim/$scene" --voxel-resolution 0 --floorplan-resolution 0
      done
      run_case sim "$root/config/sim.ini" "$out/sim/room_loop/tum" "$out/sim/room_loop/groundtruth.txt" "" \
        "$out/sim/room_loop_revisit/tum" "$out/sim/room_loop_revisit/groundtruth.txt" "" ;;
    fr1)
      seq="$data/tum_fr1_rpy_first250"
      if [ ! -f "$seq/groundtruth.txt" ]; then echo "fr1  | skipped: $seq not found"; continue; fi
      run_case fr1 "$root/config/tum_fr1.ini" "$seq" "$seq/groundtruth.txt" "--max-frames 150" \
        "$seq" "$seq/groundtruth.txt" "--first-frame 150" ;;
    *) die "unknown case '$c' (sim, fr1)" ;;
  esac
done
echo "outputs in $out"

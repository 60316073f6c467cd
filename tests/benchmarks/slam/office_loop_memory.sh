#!/usr/bin/env bash
# Benchmark: memory and per-frame cost of keygrid-slam over a long run, and the cost of
# its final step. Runs keygrid-slam once on the synthetic 44 m office_loop (3300 frames) with
# config/sim.ini (every map on: 2D ISM grid, submapped 3D grid, HOC points; sequential mode) and
# prints one markdown table row from its report.json:
#   RSS growth per keyframe [MB/kf]  least-squares slope of report.json "rss_mb_by_keyframes"
#                                    (RSS sampled every 25 keyframes in the map)
#   max RSS [MB]                     "max_rss_mb" (getrusage ru_maxrss, the final step included)
#   last 500 / first 500 frames      mean "track_and_map" time per frame (tracking, and in
#                                    sequential mode local mapping, map insertion and loop
#                                    closing) of the last 500 frames over the first 500
#                                    ("track_and_map_ms_per_100_frames")
#   final step [s]                   timings "finish": global bundle adjustment, map
#                                    re-anchoring, frame refinement (each also listed)
#   ATE [cm]                         against the scene's ground truth
# Targets: growth <= 0.5 MB/kf, max RSS <= 600 MB, last/first <= 1.2, final <= 3 s.
# Timings depend on the machine's load: run it on an idle machine, or with `nice` beside others.
#
#   tests/benchmarks/slam/office_loop_memory.sh [--build DIR] [--out DIR] [--sim DIR]
#       [--set 'SECTION.KEY=V; ...'] [--tag NAME] [--max-frames N] [--map] [--header]
#
#   --build DIR        build tree with bin/keygrid-slam (and bin/keygrid-sim to render) (default: build)
#   --out DIR          the run goes to DIR/run_<tag> (redone every time); renders to DIR/sim when
#                      --sim has none (default: /tmp/keygrid_office_memory)
#   --sim DIR          a keygrid-sim render of config/sim/office_loop.ini (DIR/tum, DIR/groundtruth.txt)
#                      (default: /tmp/keygrid_nav_safety/sim/office_loop if it exists, else DIR/sim
#                      of --out, rendered once with keygrid-sim)
#   --set OVERRIDES    keygrid-slam --set overrides, e.g. 'refinement.global_max_keyframes=0'
#                      (default: none)
#   --tag NAME         name of the run folder and of the table row (default: the build folder's name)
#   --max-frames N     stop after N frames (default: all 3300)
#   --map              also record the run into a session file (keygrid-slam --map RUN/session.kgmap)
#   --header           print the table header before the row
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
out=/tmp/keygrid_office_memory
sim=""
extraSet=""
tag=""
maxFrames=0
header=0
withMap=0
kg_parse_args --build=build --out=out --sim=sim --set=extraSet --tag=tag --max-frames=maxFrames \
  --header=header:1 --map=withMap:1 -- "$@"
kg_whole_number --max-frames "$maxFrames"
build="$(kg_build_dir "$build" keygrid-slam)" || exit 2
[ -n "$tag" ] || tag="$(basename "$(dirname "$build")")_$(basename "$build")"
mkdir -p "$out" || die "cannot create $out"

if [ -z "$sim" ]; then
  if [ -f /tmp/keygrid_nav_safety/sim/office_loop/groundtruth.txt ]; then sim=/tmp/keygrid_nav_safety/sim/office_loop
  else
    sim="$out/sim"
    if [ ! -f "$sim/groundtruth.txt" ]; then
      [ -x "$build/bin/keygrid-sim" ] || die "$build/bin/keygrid-sim not found to render office_loop"
      echo "== rendering office_loop -> $sim (once)" >&2
      rm -rf "$sim"
      "$build/bin/keygrid-sim" --quiet --scene "$root/config/sim/office_loop.ini" --output "$sim" >"$out/render.log" 2>&1 \
        || die "keygrid-sim failed: $out/render.log"
    fi
  fi
fi
[ -d "$sim/tum" ] && [ -f "$sim/groundtruth.txt" ] || die "--sim $sim has no tum/ and groundtruth.txt"

run="$out/run_$tag"
rm -rf "$run"; mkdir -p "$run"
overrides="slam.mode=sequential"
[ -n "$extraSet" ] && overrides="$overrides; $extraSet"
extra=(); [ "$maxFrames" -gt 0 ] && extra=(--max-frames "$maxFrames")
[ "$withMap" = 1 ] && extra+=(--map "$run/session.kgmap")
echo "== office_loop, $tag: keygrid-slam -> $run" >&2
"$build/bin/keygrid-slam" --quiet --config "$root/config/sim.ini" --input "$sim/tum" --output "$run" \
  --gt "$sim/groundtruth.txt" --set "$overrides" "${extra[@]}" >"$run/slam.log" 2>&1 \
  || die "keygrid-slam failed: $run/slam.log"

/usr/bin/python3 - "$run/report.json" "$tag" "$header" <<'PY'
import json, sys
import numpy as np
r = json.load(open(sys.argv[1])); tag = sys.argv[2]; t = r["timings"]
def total(k): return t[k]["total_s"] if k in t else 0.0
s = np.array(r.get("rss_mb_by_keyframes", []), dtype=float)
growth = np.polyfit(s[:, 0], s[:, 2], 1)[0] if len(s) >= 2 else float("nan")
blocks = r.get("track_and_map_ms_per_100_frames", [])
if r["frames"] % 100: blocks = blocks[:-1]  # a partial last block
ratio = float("nan")
if len(blocks) >= 10: ratio = np.mean(blocks[-5:]) / np.mean(blocks[:5])
first = np.mean(blocks[:5]) if len(blocks) >= 5 else float("nan")
last = np.mean(blocks[-5:]) if len(blocks) >= 5 else float("nan")
ok = lambda v, lim: "ok" if v <= lim else "MISSED"
if sys.argv[3] == "1":
    print("| run | frames / keyframes | RSS growth [MB/kf] | max RSS [MB] | track+map first / last 500 [ms/frame] | last / first | final step [s] (global BA / frame refinement) | global BA keyframes | ATE [cm] |")
    print("|---|---|---|---|---|---|---|---|---|")
ga = r.get("global_ba", {})
print(f"| {tag} | {r['frames']} / {r['keyframes']} | {growth:.2f} ({ok(growth, 0.5)}) | {r['max_rss_mb']:.0f} ({ok(r['max_rss_mb'], 600)}) "
      f"| {first:.1f} / {last:.1f} | {ratio:.2f} ({ok(ratio, 1.2)}) "
      f"| {total('finish'):.2f} ({ok(total('finish'), 3)}) ({total('global_bundle_adjustment'):.2f} / {total('frame_refinement'):.2f}) "
      f"| {ga.get('keyframes', 0)} | {100 * r.get('ate_rmse_m', float('nan')):.2f} |")
PY

#!/bin/bash
# HOC experiments (doc/evaluation.md "HOC point map"): the standard system ([hoc]
# enabled = false) against HOC on the dynamic keygrid-sim scenes, a static scene, and — when
# ../shared/data is present — tum_fr1_rpy_first250 and its augmented (dynamic objects) version.
# For each: TE = ATE RMSE [mm], RE = orientation RMSE [deg] (keygrid-slam report.json,
# ate_rmse_m / ate_rot_rmse_deg), TE of the online trajectory (each frame's pose as the tracker
# delivered it, before loop closing and the final bundle adjustment: trajectory_online.txt through
# keygrid-eval), final map size [landmarks], HOC CPU per frame, and the share of features on
# dynamic objects (keygrid_dynamic_feature_share on the simulator's masks).
# Usage: tests/benchmarks/hoc/run_hoc.sh [BUILD_DIR=build] [OUT_DIR=out/hoc]
# Writes OUT_DIR/hoc_table.md and OUT_DIR/<scene>_<std|hoc>/frames.csv (map size over time);
# tests/benchmarks/hoc/plot_map_size.py OUT_DIR doc/images/hoc-map-size.png draws the plot.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/hoc_configs.sh"
hoc_dirs out/hoc "$@"
DATA="${KEYGRID_SHARED_DATA:-$SRC/../shared/data}"

# Configurations: sim_std.ini / sim_hoc.ini, fr1_std.ini / fr1_hoc.ini.
write_hoc_configs "$SRC" "$OUT"

generate() {  # scene [seed]
	local dir="$OUT/seq_$1"
	[ -f "$dir/groundtruth.txt" ] && return 0
	"$BIN/keygrid-sim" --quiet --scene "$SRC/config/sim/$1.ini" --output "$dir" ${2:+--seed $2} --mask
}

run() {  # name input gt cfgprefix
	for v in std hoc; do
		"$BIN/keygrid-slam" --quiet --config "$OUT/${4}_$v.ini" --input "$2" --gt "$3" --output "$OUT/$1_$v" > "$OUT/$1_$v.log" 2>&1 || true
	done
}

declare -a ROWS=()
row() {  # name label share gt
	local line v
	# the online trajectory's ATE -> RUN/online_eval.json (left missing when it cannot be scored)
	for v in std hoc; do
		rm -f "$OUT/$1_$v/online_eval.json"
		"$BIN/keygrid-eval" --gt "$4" --est "$OUT/$1_$v/trajectory_online.txt" --json "$OUT/$1_$v/online_eval.json" > /dev/null 2>&1 || true
	done
	line=$(/usr/bin/python3 - "$OUT/$1_std" "$OUT/$1_hoc" "$2" "$3" <<'PY'
import json, os, sys
s, h = (json.load(open(os.path.join(d, "report.json"))) for d in sys.argv[1:3])
def online(d):
    p = os.path.join(d, "online_eval.json")
    return "%.1f" % (1000 * json.load(open(p))["ate_rmse_m"]) if os.path.exists(p) else "n/a"
def te(r): return "%.1f" % (1000 * r["ate_rmse_m"]) if r.get("ate_rmse_m") is not None else "n/a"
def re_(r): return "%.3f" % r["ate_rot_rmse_deg"] if r.get("ate_rot_rmse_deg") is not None else "n/a"
hoc = h["timings"].get("hoc", {})
print("| %s | %s | %s | %s | %s | %s | %s | %s | %d | %d | %d/%d | %s / %s |" % (sys.argv[3], sys.argv[4], te(s), te(h), online(sys.argv[1]) + " / " + online(sys.argv[2]), re_(s), re_(h),
      "%.1fx" % (s["landmarks"] / max(1, h["landmarks"])), s["landmarks"], h["landmarks"], s["tracked"], h["tracked"],
      hoc.get("median_ms", "n/a"), hoc.get("p95_ms", "n/a")))
PY
)
	ROWS+=("$line")
}

share() { "$BIN/keygrid_dynamic_feature_share" "$1" | sed -E 's/.*share ([0-9.]+ %).*/\1/'; }

for scene in static_camera_dynamic static_camera_crowd moving_camera_dynamic relocalization; do
	echo "== $scene" >&2
	generate "$scene"
	run "$scene" "$OUT/seq_$scene/tum" "$OUT/seq_$scene/groundtruth.txt" sim
	row "$scene" "$scene" "$(share "$OUT/seq_$scene/tum")" "$OUT/seq_$scene/groundtruth.txt"
done
echo "== room_loop (static)" >&2
generate room_loop 12
run room_loop "$OUT/seq_room_loop/tum" "$OUT/seq_room_loop/groundtruth.txt" sim
row room_loop "room_loop seed 12 (static)" "0 %" "$OUT/seq_room_loop/groundtruth.txt"
if [ -d "$DATA/tum_fr1_rpy_first250" ]; then
	echo "== tum_fr1_rpy_first250" >&2
	run fr1_rpy "$DATA/tum_fr1_rpy_first250" "$DATA/tum_fr1_rpy_first250/groundtruth.txt" fr1
	row fr1_rpy "tum_fr1_rpy_first250 (static)" "0 %" "$DATA/tum_fr1_rpy_first250/groundtruth.txt"
	echo "== augmented fr1_rpy" >&2
	[ -f "$OUT/seq_augment/groundtruth.txt" ] || "$BIN/keygrid-sim" --quiet --augment "$DATA/tum_fr1_rpy_first250" \
		--scene "$SRC/config/sim/augment_fr1_rpy.ini" --output "$OUT/seq_augment" --mask
	run augment "$OUT/seq_augment/tum" "$OUT/seq_augment/groundtruth.txt" fr1
	row augment "fr1_rpy augmented (augment_fr1_rpy.ini)" "$(share "$OUT/seq_augment/tum" 2>/dev/null || echo n/a)" "$OUT/seq_augment/groundtruth.txt"
fi

{
	echo "| sequence | features on dynamic objects | TE std [mm] | TE HOC [mm] | online TE std / HOC [mm] | RE std [deg] | RE HOC [deg] | map std/HOC | map std | map HOC | tracked std/HOC | HOC CPU median / p95 [ms/frame] |"
	echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
	printf '%s\n' "${ROWS[@]}"
} | tee "$OUT/hoc_table.md"

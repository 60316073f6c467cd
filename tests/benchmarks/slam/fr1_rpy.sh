#!/usr/bin/env bash
# Frontend benchmark on TUM fr1_rpy (first 250 frames, ../shared/data): accuracy and speed of
# keygrid-slam in sequential and threaded mode, RUNS times each, printed as a markdown table.
#   tests/benchmarks/slam/fr1_rpy.sh [BUILD_DIR] [RUNS]
# Reference (ORB-SLAM2 RGB-D, TUM1.yaml, same 250 frames, 2-core machine, see issue 4):
#   ATE 2.60 cm median of 3 runs, 250/250 tracked, tracking 15.5 ms median per frame.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
build="$(kg_build_dir "${1:-$build}" keygrid-slam)" || exit 2
runs="${2:-3}"
data="${KEYGRID_SHARED_DATA:-$root/../shared/data}/tum_fr1_rpy_first250"
[ -d "$data" ] || { echo "missing $data" >&2; exit 2; }
out="$(mktemp -d)"
echo "| mode | run | frames | tracked | ATE RMSE [cm] | fps (end to end) | extract median/p95 [ms] | track median/p95 [ms] | local mapping median [ms] | keyframes |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for mode in sequential threaded; do
  for r in $(seq 1 "$runs"); do
    "$build/bin/keygrid-slam" --quiet --mode "$mode" --config "$root/config/tum_fr1.ini" \
      --input "$data" --output "$out/$mode$r" --gt "$data/groundtruth.txt" > /dev/null
    python3 - "$out/$mode$r/report.json" "$mode" "$r" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); t = r["timings"]
g = lambda k, f: t[k][f] if k in t else float("nan")
print(f"| {sys.argv[2]} | {sys.argv[3]} | {r['frames']} | {r['tracked']} | {100*r['ate_rmse_m']:.2f} | {r['fps']:.1f} | "
      f"{g('extract','median_ms'):.1f} / {g('extract','p95_ms'):.1f} | {g('track','median_ms'):.1f} / {g('track','p95_ms'):.1f} | "
      f"{g('local_mapping','median_ms'):.1f} | {r['keyframes']} |")
PY
  done
done
rm -rf "$out"

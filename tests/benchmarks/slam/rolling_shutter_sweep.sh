#!/usr/bin/env bash
# Rolling-shutter readout calibration without ground truth: runs keygrid-slam over a range of
# [tracker] rolling_shutter_readout values (and feature budgets, to average out ORB's
# sensitivity) and prints, per readout, the median normalised residual of the final global
# bundle adjustment (report.json global_ba.median_chi2; the smallest wins) and, when the
# input has a groundtruth.txt, the ATE for comparison. See doc/frontend.md "Rolling shutter".
#   tests/benchmarks/slam/rolling_shutter_sweep.sh BUILD_DIR CONFIG.ini INPUT [READOUTS] [BUDGETS]
# e.g. tests/benchmarks/slam/rolling_shutter_sweep.sh build config/tum_fr1.ini \
#        ../shared/data/tum_fr1_rpy_first250 "0 0.01 0.015 0.02 0.025 0.03 0.035 0.04 0.05" "990 1000 1010"
set -euo pipefail
[ $# -ge 3 ] || { sed -n 2,9p "$0"; exit 2; }
build="$1"; config="$2"; input="$3"
readouts="${4:-0 0.01 0.02 0.03 0.04}"
budgets="${5:-1000}"
gt=""
[ -f "$input/groundtruth.txt" ] && gt="--gt $input/groundtruth.txt"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
echo "| readout [s] | median chi2 of the final BA (mean over budgets) | ATE [cm] per budget |"
echo "|---|---|---|"
for ro in $readouts; do
  chi=""; ate=""
  for n in $budgets; do
    # shellcheck disable=SC2086
    "$build/bin/keygrid-slam" --quiet --config "$config" --input "$input" --output "$out/r" $gt \
      --set "tracker.rolling_shutter_readout=$ro; features.num_features=$n" > /dev/null
    line=$(python3 - "$out/r/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
ate = r.get("ate_rmse_m")
print(r["global_ba"]["median_chi2"], "-" if ate is None else f"{100 * ate:.2f}")
PY
)
    chi="$chi ${line%% *}"; ate="$ate ${line##* }"
  done
  mean=$(python3 -c "import sys; v=[float(x) for x in sys.argv[1:]]; print(f'{sum(v)/len(v):.4f}')" $chi)
  echo "| $ro | $mean | ${ate# } |"
done

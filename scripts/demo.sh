#!/usr/bin/env bash
# `make demo`: the main job on data the project makes itself.
# Until keygrid-slam exists, the demo exercises the conversion and evaluation pipeline:
#   1. writes a small TUM RGB-D folder (a textured plane seen from a moving camera, with its
#      ground-truth trajectory) using keygrid-sim;
#   2. converts it to an MRPT rawlog with keygrid-tum2rawlog (readable by RawLogViewer);
#   3. evaluates a perturbed copy of the trajectory with keygrid-eval.
set -euo pipefail
build="${1:-build}"
bin="$build/bin"
out="${KEYGRID_DEMO_OUT:-out/demo}"
mkdir -p "$out"

if [ -x "$bin/keygrid-sim" ] && [ -f config/sim/room_loop.ini ]; then
  echo "== keygrid-sim: generating config/sim/room_loop.ini into $out/sim =="
  "$bin/keygrid-sim" --scene config/sim/room_loop.ini --output "$out/sim"
  tum="$out/sim/tum"
else
  echo "keygrid-sim is not built; see doc/user-guide.md" >&2
  exit 1
fi

echo "== keygrid-tum2rawlog =="
"$bin/keygrid-tum2rawlog" --input "$tum" --output "$out/sequence.rawlog"

echo "== keygrid-eval: ground truth vs itself, then vs a drifting copy =="
awk '!/^#/ && NF==8 { printf "%s %.9f %.9f %.9f %s %s %s %s\n", $1, $2*1.01, $3*1.01, $4, $5, $6, $7, $8 }' \
  "$tum/groundtruth.txt" > "$out/drifting_estimate.txt"
"$bin/keygrid-eval" --gt "$tum/groundtruth.txt" --est "$tum/groundtruth.txt"
"$bin/keygrid-eval" --gt "$tum/groundtruth.txt" --est "$out/drifting_estimate.txt" --json "$out/eval.json"

echo
echo "Outputs in $out:"
echo "  sequence.rawlog           open with: RawLogViewer $out/sequence.rawlog"
echo "  $tum/                     TUM layout (rgb/, depth/, groundtruth.txt)"
echo "  eval.json                 ATE/RPE of the 1 %-scaled trajectory"

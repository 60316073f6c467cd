#!/usr/bin/env bash
# Builds keygrid's default ORB vocabulary from images the project generates itself: keygrid-sim
# renders of the training scenes in config/vocab/ (not the evaluation scenes of config/sim/),
# two seeds each (the seed changes every texture and the sensor noise), every 2nd frame.
# Deterministic: the same build gives the same bytes (rendering, PNG, ORB and the tree training
# are all seeded; the training is thread-count independent). See doc/loop-closure.md.
#
#   scripts/make-default-vocabulary.sh BUILD OUT.bin [LEVELS]
#
# BUILD: build folder with bin/keygrid-sim and bin/keygrid-vocab. LEVELS: tree depth (default 4;
# k = 10). Renders into a temporary folder (about 0.7 GB while it runs), removed at the end;
# with KEYGRID_VOCAB_WORK=DIR the renders go to DIR, are kept and are reused by the next run.
set -euo pipefail

if [[ $# -lt 2 || $# -gt 3 ]]; then
	echo "usage: $0 BUILD OUT.bin [LEVELS]" >&2
	exit 2
fi
BUILD=$(cd "$1" && pwd)
OUT=$2
LEVELS=${3:-4}
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SIM="$BUILD/bin/keygrid-sim"
VOCAB="$BUILD/bin/keygrid-vocab"
for t in "$SIM" "$VOCAB"; do [[ -x $t ]] || { echo "$t not found (build keygrid-sim keygrid-vocab)" >&2; exit 1; }; done

if [[ -n ${KEYGRID_VOCAB_WORK:-} ]]; then
	WORK=$KEYGRID_VOCAB_WORK
	mkdir -p "$WORK"
else
	WORK=$(mktemp -d "${TMPDIR:-/tmp}/keygrid-vocab-XXXXXX")
	trap 'rm -rf "$WORK"' EXIT
fi
t0=$SECONDS
# scene:seed pairs; 240 frames each
RENDERS="training_hall:101 training_hall:102 training_storage:202 training_storage:203"
: >"$WORK/images.txt"
for r in $RENDERS; do
	scene=${r%%:*}
	seed=${r##*:}
	[[ -s $WORK/${scene}_$seed/tum/rgb.txt ]] ||
		"$SIM" --scene "$ROOT/config/vocab/$scene.ini" --seed "$seed" --output "$WORK/${scene}_$seed" --quiet
	# every 2nd frame; rgb.txt lists the frames in time order
	awk -v d="${scene}_$seed/tum" '!/^#/ && NF >= 2 && (n++ % 2 == 0) { print d "/" $2 }' \
		"$WORK/${scene}_$seed/tum/rgb.txt" >>"$WORK/images.txt"
done
tRender=$((SECONDS - t0))
"$VOCAB" train --images "$WORK/images.txt" --k 10 --levels "$LEVELS" --features orb --nfeatures 1000 \
	--seed 1 --output "$OUT"
echo "$(wc -l <"$WORK/images.txt") images; render ${tRender} s, total $((SECONDS - t0)) s; $(stat -c %s "$OUT") bytes -> $OUT"

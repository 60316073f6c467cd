#!/usr/bin/env bash
# Loop-detection precision/recall of keygrid-slam on the keygrid-sim loops (and false loops on
# TUM fr1_rpy), for several vocabulary choices. Definitions: doc/loop-closure.md, loop_pr.py.
#
#   tests/benchmarks/loop/loop_pr.sh BUILD OUT
#
# BUILD: a build folder with bin/keygrid-sim, bin/keygrid-slam, bin/keygrid-vocab.
# OUT:   work folder. OUT/sim/<seq>/ (renders, reused when present: delete to re-render),
#        OUT/vocab/ (pre-pass vocabularies), OUT/runs/<mode>/<seq>/ (keygrid-slam outputs +
#        loop_pr.json), OUT/tables.md (the markdown tables, also printed).
# Environment:
#   LOOP_PR_MODES    vocabulary choices, default "train self4":
#                      train      [loop_closing] vocabulary = train (in-run, first keyframes)
#                      selfL      pre-pass: keygrid-vocab train --tum SEQ --every 5 --levels L
#                      NAME=FILE  vocabulary = FILE (e.g. the shipped default), labelled NAME
#   LOOP_PR_SEQS     subset of sequences (default: all, see SEQS below)
#   LOOP_PR_RENDER_ONLY=1  only render the sequences
#   LOOP_PR_TUM      TUM fr1_rpy folder (default /work/shared/data/tum_fr1_rpy_first250;
#                    skipped when absent)
# Runs are sequential (one keygrid-slam at a time).
set -euo pipefail

if [[ $# -ne 2 ]]; then
	echo "usage: $0 BUILD OUT" >&2
	exit 2
fi
BUILD=$(cd "$1" && pwd)
OUT=$2
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
SIM="$BUILD/bin/keygrid-sim"
SLAM="$BUILD/bin/keygrid-slam"
VOCAB="$BUILD/bin/keygrid-vocab"
PR="$HERE/loop_pr.py"
# numpy: Debian's python3-numpy (a pyenv python3 first in PATH may lack it)
PY=${PYTHON:-$(command -v /usr/bin/python3 || command -v python3)}
TUM=${LOOP_PR_TUM:-/work/shared/data/tum_fr1_rpy_first250}
MODES=${LOOP_PR_MODES:-"train self4"}

# name | scene | seed (empty: the scene's)
SEQS_ALL="room_loop_s11:room_loop:11 room_loop_s12:room_loop:12 room_loop_s13:room_loop:13
corridor_loop:corridor_loop: room_survey:room_survey: relocalization:relocalization: fr1_rpy::"
SEQS=${LOOP_PR_SEQS:-$(echo $SEQS_ALL | tr '\n' ' ' | sed 's/:[^ ]*//g')}

spec_of() {
	local s
	for s in $SEQS_ALL; do [[ ${s%%:*} == "$1" ]] && { echo "$s"; return; }; done
	echo "unknown sequence $1" >&2
	exit 2
}

# Render (once) and print the TUM folder and the ground truth of a sequence.
prepare() {
	local name=$1 spec scene seed dir
	spec=$(spec_of "$name")
	scene=$(echo "$spec" | cut -d: -f2)
	seed=$(echo "$spec" | cut -d: -f3)
	if [[ -z $scene ]]; then
		echo "$TUM $TUM/groundtruth.txt"
		return
	fi
	dir="$OUT/sim/$name"
	if [[ ! -s $dir/groundtruth.txt || ! -d $dir/tum ]]; then
		local t0=$SECONDS
		"$SIM" --scene "$ROOT/config/sim/$scene.ini" ${seed:+--seed "$seed"} --output "$dir" \
			--voxel-resolution 0 --floorplan-resolution 0 --quiet >&2
		rm -f "$dir/sequence.rawlog"  # keygrid-slam reads tum/; the rawlog only costs disk
		echo "rendered $name in $((SECONDS - t0)) s" >&2
	fi
	echo "$dir/tum $dir/groundtruth.txt"
}

base_config() {
	if [[ $1 == fr1_rpy ]]; then echo "$ROOT/config/tum_fr1.ini"; else echo "$ROOT/config/sim.ini"; fi
}

# keygrid-slam has no --set: the run's config is a copy of the base with [loop_closing] appended.
make_config() {
	local base=$1 vocab=$2 out=$3
	if grep -q '^\[loop_closing\]' "$base"; then
		echo "$base already has [loop_closing]: extend make_config" >&2
		exit 1
	fi
	{
		cat "$base"
		printf '\n[loop_closing]\nvocabulary = %s\n' "$vocab"
	} >"$out"
}

if [[ ${LOOP_PR_RENDER_ONLY:-0} == 1 ]]; then
	for s in $SEQS; do [[ $s == fr1_rpy && ! -d $TUM ]] || prepare "$s" >/dev/null; done
	exit 0
fi

JSONS=()
for mode in $MODES; do
	for s in $SEQS; do
		if [[ $s == fr1_rpy && ! -d $TUM ]]; then
			echo "skipping fr1_rpy: $TUM absent" >&2
			continue
		fi
		read -r input gt < <(prepare "$s")
		label=${mode%%=*}
		run="$OUT/runs/$label/$s"
		mkdir -p "$run" "$OUT/vocab" "$OUT/cfg"
		vocab_seconds=0
		case $mode in
		train) vocab=train ;;
		*=*) vocab=$(cd "$(dirname "${mode#*=}")" && pwd)/$(basename "${mode#*=}") ;;
		self[0-9])
			vocab="$OUT/vocab/${s}_$mode.bin"
			t0=$(date +%s.%N)
			"$VOCAB" train --tum "$input" --every 5 --levels "${mode#self}" --output "$vocab" >/dev/null 2>&1
			vocab_seconds=$(echo "$(date +%s.%N) - $t0" | bc)
			;;
		*)
			echo "unknown mode $mode" >&2
			exit 2
			;;
		esac
		cfg="$OUT/cfg/${s}_$label.ini"
		make_config "$(base_config "$s")" "$vocab" "$cfg"
		"$SLAM" --config "$cfg" --input "$input" --output "$run" --gt "$gt" --quiet >"$run/stdout.txt" 2>&1 ||
			echo "keygrid-slam failed on $s ($mode), see $run/stdout.txt" >&2
		"$PY" "$PR" score --run "$run" --gt "$gt" --name "$s" --mode "$label" \
			--vocab-seconds "$vocab_seconds" --json "$run/loop_pr.json"
		JSONS+=("$run/loop_pr.json")
	done
done
"$PY" "$PR" table "${JSONS[@]}" | tee "$OUT/tables.md"

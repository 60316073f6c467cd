# Sourced by the HOC benchmark scripts, which take the folders as positional arguments
# (SCRIPT [BUILD_DIR=build] [OUT_DIR]).
source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"

# Usage: hoc_dirs DEFAULT_OUT [BUILD_DIR [OUT_DIR]]: sets SRC (the source tree), BUILD (checked to hold bin/keygrid-slam), BIN = BUILD/bin and
# OUT (OUT_DIR or SRC/DEFAULT_OUT, created).
hoc_dirs() {
	local defaultOut="$1"
	shift
	[ $# -le 2 ] || die "at most two arguments, BUILD_DIR and OUT_DIR (see --help)"
	SRC="$root"
	BUILD="$(kg_build_dir "${1:-$build}" keygrid-slam)" || exit 2
	BIN="$BUILD/bin"
	OUT="${2:-$SRC/$defaultOut}"
	mkdir -p "$OUT" || die "cannot create $OUT"
}

# Writes the std / HOC keygrid-slam configurations into OUT_DIR: config/sim.ini without its maps
# (they do not change the trajectory) and config/tum_fr1.ini, each with [hoc] enabled = false
# (sim_std.ini, fr1_std.ini) / true (sim_hoc.ini, fr1_hoc.ini).
# Usage: write_hoc_configs SRC_DIR OUT_DIR
write_hoc_configs() {
	local src="$1" out="$2" f
	sed '/^\[MappingApplication/,$d' "$src/config/sim.ini" > "$out/sim_std.ini"
	cp "$out/sim_std.ini" "$out/sim_hoc.ini"
	cp "$src/config/tum_fr1.ini" "$out/fr1_std.ini"
	cp "$src/config/tum_fr1.ini" "$out/fr1_hoc.ini"
	for f in sim fr1; do
		printf '\n[hoc]\nenabled = false\n' >> "$out/${f}_std.ini"
		printf '\n[hoc]\nenabled = true\n' >> "$out/${f}_hoc.ini"
	done
}

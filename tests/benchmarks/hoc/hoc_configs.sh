# Sourced by the HOC benchmark scripts: writes the std / HOC keygrid-slam configurations into
# OUT_DIR: config/sim.ini without its maps (they do not change the trajectory) and
# config/tum_fr1.ini, each with [hoc] enabled = false (sim_std.ini, fr1_std.ini) / true
# (sim_hoc.ini, fr1_hoc.ini).
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

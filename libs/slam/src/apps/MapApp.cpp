#include <keygrid/core/CommandLine.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/SessionExport.h>
#include <keygrid/slam/apps/MapApp.h>
#include <keygrid/store/SessionStore.h>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>

namespace keygrid::slam
{
namespace
{
namespace fs = std::filesystem;

int info(const std::string& path)
{
	const auto store = store::SessionStore::Open(path);
	const auto& m = store.meta();
	const auto& c = m.camera;
	const auto n = store.counts();
	const auto bytes = fs::file_size(path);
	std::cout << std::setprecision(10) << path << "\n"
			  << "  schema_version     " << m.schemaVersion << "\n"
			  << "  keygrid_version    " << m.keygridVersion << "\n"
			  << "  created_utc        " << m.createdUtc << "\n"
			  << "  vocabulary         " << (m.vocabulary.empty() ? "(none)" : m.vocabulary.fileName) << " hash "
			  << m.vocabulary.hash << " words " << m.vocabulary.words
			  << (store.hasStoredVocabulary() ? " (stored in the file)" : "") << "\n"
			  << "  camera             " << c.name << " " << c.width << "x" << c.height << " fx " << c.fx << " fy " << c.fy
			  << " cx " << c.cx << " cy " << c.cy << " k1 " << c.dist[0] << " k2 " << c.dist[1] << " p1 " << c.dist[2]
			  << " p2 " << c.dist[3] << " k3 " << c.dist[4] << " depth_units " << std::setprecision(7) << c.depthUnits << "\n"
			  << "  keyframes          " << n.keyframes << " (" << n.keyframesWithImages << " with images)\n"
			  << "  landmarks          " << n.landmarks << "\n"
			  << "  covisibility edges " << n.covisibilityEdges << "\n"
			  << "  loop constraints   " << n.loopConstraints << "\n"
			  << "  snapshots          " << n.snapshots << "\n";
	for (const auto& name : store.snapshotNames())
	{
		const auto s = store.loadSnapshot(name);
		std::cout << "    " << name << ": " << s->data.size() / 1024 << " KiB, up to keyframe " << s->lastKeyFrame << "\n";
	}
	for (const auto& [k, v] : m.attributes) std::cout << "  " << std::left << std::setw(27) << k << v << "\n";
	std::cout << std::setprecision(4) << "  file size          " << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MiB";
	if (n.keyframes > 0) std::cout << " (" << static_cast<double>(bytes) / 1024.0 / static_cast<double>(n.keyframes) << " KiB per keyframe)";
	std::cout << "\n";
	return 0;
}

/** Open()'s checks, then every record read back and the references between them. */
int check(const std::string& path, bool images)
{
	const auto store = store::SessionStore::Open(path);
	const auto kfs = store.loadKeyFrames();
	std::set<store::KeyFrameId> ids;
	for (const auto& kf : kfs) ids.insert(kf.id);
	const auto lms = store.loadLandmarks();
	std::set<store::LandmarkId> lmIds;
	for (const auto& lm : lms)
	{
		lmIds.insert(lm.id);
		for (const auto& [kf, kp] : lm.observations)
			if (!ids.count(kf))
				throw std::runtime_error("'" + path + "': landmark " + std::to_string(lm.id) + " is observed by keyframe " +
										 std::to_string(kf) + ", which is not stored");
	}
	for (const auto& kf : kfs)
		for (const auto lm : kf.landmarks)
			if (lm != store::kNoLandmark && !lmIds.count(lm))
				throw std::runtime_error("'" + path + "': keyframe " + std::to_string(kf.id) + " refers to landmark " +
										 std::to_string(lm) + ", which is not stored");
	const auto edges = store.loadCovisibility();
	for (const auto& e : edges)
		if (!ids.count(e.a) || !ids.count(e.b))
			throw std::runtime_error("'" + path + "': covisibility edge " + std::to_string(e.a) + "-" + std::to_string(e.b) +
									 " names a keyframe that is not stored");
	const auto loops = store.loadLoopConstraints();
	for (const auto& name : store.snapshotNames()) store.loadSnapshot(name);
	store.loadVocabulary();
	if (images)
		for (const auto& kf : kfs) store.loadImages(kf.id);
	std::cout << path << ": ok (schema version " << store.meta().schemaVersion << ", " << kfs.size() << " keyframes, "
			  << lms.size() << " landmarks, " << edges.size() << " covisibility edges, " << loops.size() << " loop constraints"
			  << (images ? ", images decoded" : "") << ")\n";
	return 0;
}
int exportTo(const std::string& path, const std::string& dir)
{
	const auto r = exportSession(path, dir);
	std::cout << path << ": " << r.keyframes << " keyframes, " << r.landmarks << " landmarks, " << r.simpleMapEntries
			  << " keyframes with images in keyframes.simplemap\n";
	for (const auto& [name, kf] : r.snapshots) std::cout << "  map " << name << " as of keyframe " << kf << "\n";
	std::cout << "outputs in " << dir << ":";
	for (const auto& f : r.files) std::cout << " " << f;
	std::cout << "\n";
	return 0;
}
}  // namespace

int MapApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-map", [&] {
		core::CommandLine cl(
			"keygrid-map",
			"Inspects keygrid session files (keygrid-slam --map FILE; doc/session-store.md).\n"
			"  keygrid-map info FILE     meta table (versions, vocabulary, camera), row counts, sizes\n"
			"  keygrid-map check FILE    version + integrity checks, every record read back;\n"
			"                            exit 1 with the reason when one fails\n"
			"  keygrid-map export FILE --output DIR\n"
			"                            keyframes.txt, the maps of the last snapshot (map_2d.*, map_3d.*,\n"
			"                            hoc_points.*), keyframes.simplemap; also from a killed run's file");
		cl.positionals("info FILE | check FILE | export FILE", "sub-command and the session file")
			.flag("images", "check: also decode every keyframe's images")
			.option("output", "DIR", "export: output folder, created if missing");
		if (!cl.parse(argc, argv)) return 0;
		const auto& pos = cl.positional();
		if (pos.empty()) throw core::CommandLineError("missing sub-command (info or check)");
		if (pos[0] != "info" && pos[0] != "check" && pos[0] != "export") throw core::CommandLineError("unknown sub-command '" + pos[0] + "'");
		if (pos.size() != 2) throw core::CommandLineError(pos[0] + " needs exactly one session file");
		if (pos[0] == "export")
		{
			if (!cl.has("output")) throw core::CommandLineError("export needs --output DIR");
			return exportTo(pos[1], cl.get("output"));
		}
		if (cl.has("output")) throw core::CommandLineError("--output is for export");
		return pos[0] == "info" ? info(pos[1]) : check(pos[1], cl.flagSet("images"));
	});
}

}  // namespace keygrid::slam

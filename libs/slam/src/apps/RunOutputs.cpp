#include <keygrid/core/AtomicOutput.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/slam/SceneExport.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <keygrid/slam/System.h>
#include <keygrid/slam/apps/RunOutputs.h>

#include <cstdio>
#include <sstream>

namespace keygrid::slam
{
bool RunOutputs::write(const std::function<void()>& write)
{
	try
	{
		write();
		return true;
	}
	catch (const std::exception& e)
	{
		m_errors.push_back(e.what());
		return false;
	}
}

bool RunOutputs::text(const std::string& file, const std::string& content)
{
	return write([&] { core::writeFileAtomically(path(file), content); });
}

namespace
{
std::string floorTrajectoryText(const core::Trajectory& traj, const mrpt::poses::CPose3D& T_world_floor)
{
	std::ostringstream t;
	t << "# keygrid-slam trajectory in the floor frame (z up, z = 0 on the floor), every frame\n# "
	  << maps::floorFrameComment(T_world_floor) << "\n# timestamp tx ty tz qx qy qz qw  (T_floor_cam, optical frame)\n";
	for (const auto& p : traj) t << core::tumLine({p.t, p.T_world_cam - T_world_floor}) << "\n";
	return t.str();
}

std::string framesCsv(const System& sys)
{
	std::ostringstream csv;
	// Localization mode: a last column says whether each frame was localized in the map.
	csv << "index,timestamp,tracked,method,matches,inliers,new_keyframe,reference_keyframe,landmarks"
		<< (sys.localizeOnly() ? ",status\n" : "\n");
	for (const auto& f : sys.frames())
	{
		char line[180];
		std::snprintf(line, sizeof(line), "%zu,%.6f,%d,%s,%d,%d,%d,%lld,%zu%s\n", f.index, f.timestamp, f.tracked ? 1 : 0,
					  sfm::toString(f.method), f.matches, f.inliers, f.newKeyFrame ? 1 : 0,
					  f.hasReference ? static_cast<long long>(f.reference) : -1LL, f.mapLandmarks,
					  !sys.localizeOnly() ? "" : f.tracked ? ",localized" : ",lost");
		csv << line;
	}
	return csv.str();
}

/** Why each keyframe did or did not close a loop (doc/loop-closure.md, "Diagnostics"). */
std::string loopQueriesCsv(const loop::LoopCloser& loop)
{
	std::ostringstream csv;
	csv << "keyframe,frame,outcome,reference_score,candidates,best_candidate,best_score,verified_candidate,matches,inliers,query_ms,seen_through,verified\n";
	for (const auto& q : loop.queries())
	{
		char line[256];
		std::snprintf(line, sizeof(line), "%llu,%zu,%s,%.4f,%d,%s,%.4f,%s,%d,%d,%.3f,%.4f,%d\n", static_cast<unsigned long long>(q.keyframe),
					  q.frameIndex, toString(q.outcome), q.referenceScore, q.candidates,
					  q.candidates ? std::to_string(q.bestCandidate).c_str() : "", q.bestScore,
					  q.verifiedCandidate ? std::to_string(*q.verifiedCandidate).c_str() : "", q.matches, q.inliers,
					  1e3 * q.querySeconds, q.seenThroughRatio, q.verifiedCount);
		csv << line;
	}
	return csv.str();
}
}  // namespace

void writeRunFiles(System& sys, const SlamConfig& cfg, const RunFilesInput& in, RunOutputs& out)
{
	auto tum = [&](const char* file, const core::Trajectory& t, const std::string& header) {
		out.write([&] { core::writeTumTrajectory(out.path(file), t, header); });
	};
	tum("trajectory.txt", in.trajectory, in.trajectoryTitle);
	// The run's floor frame (any map configured): every map output is written in it.
	if (in.T_world_floor) out.text("trajectory_floor.txt", floorTrajectoryText(in.trajectory, *in.T_world_floor));
	{
		// As tracked, before later map refinement (diagnostics: trajectory.txt is the final one).
		core::Trajectory raw;
		for (const auto& f : sys.frames()) raw.push_back({f.timestamp, f.T_world_cam});
		tum("trajectory_online.txt", raw, "keygrid-slam online poses (as tracked)");
	}
	out.text("frames.csv", framesCsv(sys));
	std::string log;
	for (const auto& line : sys.initializationLog()) log += "initialization: " + line + "\n";
	if (sys.metricScale())
		for (const auto& line : sys.metricScale()->log()) log += "metric scale: " + line + "\n";
	if (!log.empty()) out.text("slam.log", log);
	tum("keyframes.txt", sys.keyframeTrajectory(), "keygrid-slam keyframes");
	// A loaded map's keyframes have their images in the session file, not here.
	if (!sys.localizeOnly())
		out.write([&] { writeKeyframesSimpleMap(sys.map(), sys.keyFrameImages(), out.path("keyframes.simplemap")); });
	out.write([&] {
		writeRunScene(in.trajectory, sys.map(), sys.metricMaps() ? &sys.metricMaps()->maps() : nullptr, in.T_world_floor, out.path("scene.3Dscene"));
	});
	if (sys.loopCloser()) out.text("loop_queries.csv", loopQueriesCsv(*sys.loopCloser()));
	if (sys.loopCloser() && sys.loopCloser()->lastPoseGraph())
		out.write([&] { sys.loopCloser()->lastPoseGraph()->writeG2o(out.path("posegraph.g2o")); });
	if (sys.metricMaps()) out.write([&] { sys.metricMaps()->writeOutputs(out.dir()); });
	// The HOC landmarks are written also when no hocPointsMap is configured.
	const bool hocMapConfigured = sys.metricMaps() && sys.metricMaps()->maps().mapByClass<CHOCPointsMap>();
	if (in.hocEnabled && !hocMapConfigured)
		out.write([&] {
			hocPointsFromLandmarks(sys.map(), cfg.tracker.hoc)
				.saveAsPly(out.path("hoc_points.ply"), in.T_world_floor ? maps::floorExportFrame(*in.T_world_floor) : maps::ExportFrame{});
		});
}

}  // namespace keygrid::slam

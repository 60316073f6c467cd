/** \file MapSession_unittest.cpp
 * Map sessions end to end on synthetic data with ground truth: keygrid-slam --map records a run
 * of room_loop; --load-map --localize tracks a second path through the same room
 * (config/sim/room_loop_revisit.ini) in that map, without re-alignment and without changing the
 * file; a mapping run killed with SIGKILL leaves a session that opens with its keyframes.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <keygrid/store/SessionStore.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "TestData.h"

using namespace keygrid;

namespace
{
std::string fileBytes(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

bool render(const std::string& scene, int frames, const std::string& out, std::string* log)
{
	return test::runCommand(
			   test::toolPath("keygrid-sim") + " --quiet --frames " + std::to_string(frames) + " --scene " + test::sourceDir() +
				   "/config/sim/" + scene + ".ini --output " + out,
			   log) == 0;
}
}  // namespace

TEST(MapSession, MapOnceThenLocalizeASecondPathInTheStoredMapsFrame)
{
	const std::string dir = test::scratchDir("map_session");
	std::string log;
	ASSERT_TRUE(render("room_loop", 240, dir + "/map_seq", &log)) << log;
	ASSERT_TRUE(render("room_loop_revisit", 240, dir + "/loc_seq", &log)) << log;

	slam::SlamRunOptions m;
	m.configPath = test::sourceDir() + "/config/sim.ini";
	m.input = dir + "/map_seq/sequence.rawlog";
	m.output = dir + "/map_out";
	m.mapFile = dir + "/room.kgmap";
	m.quiet = true;
	const auto mr = slam::runSlam(m);
	ASSERT_TRUE(mr.error.empty()) << mr.error;
	ASSERT_EQ(mr.tracked, mr.frames);
	{
		// The file holds the run's final map: every keyframe at its final pose.
		const auto session = store::SessionStore::Open(m.mapFile);
		const auto kfs = core::readTumTrajectory(m.output + "/keyframes.txt");
		const auto stored = session.loadKeyFrames();
		ASSERT_EQ(stored.size(), kfs.size());
		for (std::size_t k = 0; k < kfs.size(); k++)
			EXPECT_LT((stored[k].T_world_cam.asVectorVal() - kfs[k].T_world_cam.asVectorVal()).norm(), 1e-6);
		EXPECT_EQ(session.counts().keyframesWithImages, kfs.size());
		EXPECT_FALSE(session.snapshotNames().empty());
		EXPECT_EQ(session.meta().attributes.count("run.tracking_share_median"), 1u);
	}
	// Exported from the file, the map outputs are the run's own, byte for byte.
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-map") + " export " + m.mapFile + " --output " + dir + "/export", &log), 0) << log;
	for (const char* f : {"map_2d.pgm", "map_2d.yaml", "map_3d.bt", "map_3d.ply", "hoc_points.ply", "keyframes.simplemap"})
		EXPECT_EQ(fileBytes(dir + "/export/" + f), fileBytes(m.output + "/" + f)) << f;
	const std::string before = fileBytes(m.mapFile);

	slam::SlamRunOptions l;
	l.configPath = m.configPath;
	l.input = dir + "/loc_seq/sequence.rawlog";
	l.output = dir + "/loc_out";
	l.loadMap = m.mapFile;
	l.localize = true;
	l.quiet = true;
	const auto lr = slam::runSlam(l);
	ASSERT_TRUE(lr.error.empty()) << lr.error;
	EXPECT_EQ(fileBytes(m.mapFile), before) << "localization leaves the stored session unchanged";
	EXPECT_GE(lr.tracked, lr.frames * 95 / 100) << "localized " << lr.tracked << " of " << lr.frames;
	EXPECT_EQ(lr.localized, lr.tracked);
	const std::string report = test::readTextFile(l.output + "/report.json");
	EXPECT_NE(report.find("\"mode\": \"localize\""), std::string::npos) << report;
	EXPECT_NE(report.find("\"keyframes_created\": 0"), std::string::npos) << "localization adds no keyframe";

	// Errors in the map's frame: fixed by the mapping run against its ground truth, then the
	// second run measured in it without any fit of its own.
	const auto gt1 = core::readTumTrajectory(dir + "/map_seq/groundtruth.txt");
	const auto gt2 = core::readTumTrajectory(dir + "/loc_seq/groundtruth.txt");
	eval::TrajectoryErrorOptions o;
	o.fixedAlignment = eval::alignTrajectoryPoses(gt1, core::readTumTrajectory(m.output + "/trajectory.txt"));
	const auto e = eval::evaluateTrajectory(gt2, core::readTumTrajectory(l.output + "/trajectory.txt"), o);
	EXPECT_EQ(e.matched, lr.localized);
	EXPECT_LT(e.ate.rmse, 0.01) << e.toText();
	EXPECT_LT(e.ate.max, 0.03) << e.toText();
}

TEST(MapSession, AMappingRunKilledWithSigkillLeavesASessionThatOpens)
{
	const std::string dir = test::scratchDir("map_session_kill");
	std::string log;
	// Fast motion is fine: only the first keyframes matter.
	ASSERT_TRUE(render("room_loop", 150, dir + "/seq", &log)) << log;
	const std::string file = dir + "/killed.kgmap";
	const pid_t pid = ::fork();
	ASSERT_GE(pid, 0);
	if (pid == 0)
	{
		const std::string tool = test::toolPath("keygrid-slam");
		const std::string cfg = test::sourceDir() + "/config/sim.ini";
		const std::string in = dir + "/seq/sequence.rawlog";
		const std::string out = dir + "/out";
		::execl(tool.c_str(), tool.c_str(), "--quiet", "--config", cfg.c_str(), "--input", in.c_str(), "--output", out.c_str(), "--map",
				file.c_str(), static_cast<char*>(nullptr));
		::_exit(127);
	}
	// Kill once the file holds at least N keyframes (read by a second connection while the run
	// writes: WAL readers see every committed keyframe).
	constexpr std::size_t N = 6;
	std::size_t seen = 0;
	const auto start = std::chrono::steady_clock::now();
	while (seen < N && std::chrono::steady_clock::now() - start < std::chrono::minutes(5))
	{
		std::this_thread::sleep_for(std::chrono::milliseconds(50));
		if (!std::filesystem::exists(file)) continue;
		try
		{
			store::SessionStoreOptions ro;
			ro.integrityCheck = "none";
			seen = store::SessionStore::Open(file, store::SessionStore::Mode::ReadOnly, ro).counts().keyframes;
		}
		catch (const std::exception&)
		{
			// Created but not yet initialised: try again.
		}
	}
	ASSERT_EQ(::kill(pid, SIGKILL), 0);
	int status = 0;
	ASSERT_EQ(::waitpid(pid, &status, 0), pid);
	ASSERT_GE(seen, N) << "the run did not write " << N << " keyframes in time";
	ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";

	EXPECT_NO_THROW(store::SessionStore::Check(file));
	const auto session = store::SessionStore::Open(file);
	sfm::SparseMap map;
	const auto loaded = slam::loadSparseMap(session, map);
	EXPECT_GE(loaded.keyframes, N);
	EXPECT_GT(loaded.landmarks, 100u);
	for (const auto& [id, kf] : map.keyframes()) EXPECT_FALSE(session.loadImages(id).depthRaw.empty()) << "keyframe " << id;
	EXPECT_EQ(test::runCommand(test::toolPath("keygrid-map") + " check " + file, &log), 0) << log;
	// The outputs of what was mapped until the kill: the keyframes, their images, the landmarks.
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-map") + " export " + file + " --output " + dir + "/export", &log), 0) << log;
	EXPECT_EQ(core::readTumTrajectory(dir + "/export/keyframes.txt").size(), loaded.keyframes);
	EXPECT_TRUE(std::filesystem::exists(dir + "/export/keyframes.simplemap"));
	EXPECT_TRUE(std::filesystem::exists(dir + "/export/hoc_points.ply"));
}

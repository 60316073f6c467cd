/** \file MapExtend_unittest.cpp
 * Extend mode end to end (keygrid-slam --load-map FILE without --localize) on synthetic data
 * with ground truth: a second run of room_loop that starts where the stored map has never
 * looked maps on in a frame of its own, and is merged into the stored map when it comes back
 * to a place the stored map knows; FILE then holds both, in one frame.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <keygrid/store/SessionStore.h>

#include <string>

#include "TestData.h"

using namespace keygrid;

TEST(MapExtend, ASecondRunStartedInUnseenSpaceIsMergedIntoTheStoredMap)
{
#if KEYGRID_TESTS_SANITIZED
	GTEST_SKIP() << "sanitized build: two SLAM runs of 350 frames take minutes (the merge's parts have unit tests)";
#endif
	const std::string dir = test::scratchDir("map_extend");
	std::string log;
	// room_loop: a 6 m circle looking outwards; frames 0-149 see one third of the room, frames
	// 250-449 another third and then, at the end of the circle, the start again.
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-sim") + " --quiet --scene " + test::sourceDir() + "/config/sim/room_loop.ini --output " + dir + "/seq", &log), 0) << log;
	const auto gt = core::readTumTrajectory(dir + "/seq/groundtruth.txt");

	slam::SlamRunOptions m;
	m.configPath = test::sourceDir() + "/config/sim.ini";
	m.input = dir + "/seq/sequence.rawlog";
	m.output = dir + "/first";
	m.mapFile = dir + "/room.kgmap";
	m.maxFrames = 150;
	m.quiet = true;
	const auto mr = slam::runSlam(m);
	ASSERT_TRUE(mr.error.empty()) << mr.error;
	const std::size_t storedKeyFrames = store::SessionStore::Open(m.mapFile).counts().keyframes;

	slam::SlamRunOptions x;
	x.configPath = m.configPath;
	x.input = m.input;
	x.output = dir + "/extend";
	x.loadMap = m.mapFile;
	x.firstFrame = 250;
	x.quiet = true;
	const auto xr = slam::runSlam(x);
	ASSERT_TRUE(xr.error.empty()) << xr.error;
	const std::string report = test::readTextFile(x.output + "/report.json");
	EXPECT_NE(report.find("\"mode\": \"extend\""), std::string::npos) << report;
	EXPECT_NE(report.find("\"started\": \"new_map\""), std::string::npos) << report;
	EXPECT_NE(report.find("\"maps_merged\": 1"), std::string::npos) << report;
	EXPECT_NE(report.find("\"keyframes_waiting_for_merge\": 0"), std::string::npos) << report;

	// The file holds the merged map: every keyframe of the run's final map, at its final pose.
	const auto kfs = core::readTumTrajectory(x.output + "/keyframes.txt");
	const auto session = store::SessionStore::Open(m.mapFile);
	const auto stored = session.loadKeyFrames();
	ASSERT_EQ(stored.size(), kfs.size());
	EXPECT_GT(stored.size(), storedKeyFrames);
	for (std::size_t k = 0; k < kfs.size(); k++)
		EXPECT_LT((stored[k].T_world_cam.asVectorVal() - kfs[k].T_world_cam.asVectorVal()).norm(), 1e-6) << "keyframe " << k;
	EXPECT_EQ(session.counts().keyframesWithImages, kfs.size());

	// One frame: the merged keyframes against ground truth with one fit, and the second run's
	// frames in the frame the first run fixed (no fit of their own).
	const auto all = eval::evaluateTrajectory(gt, kfs);
	EXPECT_LT(all.ate.rmse, 0.01) << all.toText();
	eval::TrajectoryErrorOptions o;
	o.fixedAlignment = eval::alignTrajectoryPoses(gt, core::readTumTrajectory(m.output + "/trajectory.txt"));
	const auto second = eval::evaluateTrajectory(gt, core::readTumTrajectory(x.output + "/trajectory.txt"), o);
	EXPECT_GE(second.matched, 150u);
	EXPECT_LT(second.ate.rmse, 0.02) << second.toText();
	// The merged maps are written in the stored map's frame too.
	EXPECT_EQ(test::runCommand(test::toolPath("keygrid-map") + " check " + m.mapFile, &log), 0) << log;
}

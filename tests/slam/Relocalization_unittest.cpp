// Relocalization through the vocabulary tree: a "kidnapped" sequence jumps from the
// far side of a generated room loop back to views of its start, which only old keyframes
// show. The tracker must find them through the loop closer's keyframe database and continue
// at the true pose (aligned on the part before the jump, so a look-alike place would show).
#include <keygrid/core/TumText.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/system/filesystem.h>

#include <nlohmann/json.hpp>

#include "SimSlamRun.h"
#include "TestData.h"

#include <cstdio>
#include <fstream>
#include <regex>

using namespace keygrid;

TEST(Relocalization, KidnappedCameraIsRelocalizedOnOldKeyframesThroughTheVocabulary)
{
	const std::string dir = test::scratchDir("reloc_kidnap");
	std::string log;
	ASSERT_EQ(
		test::runCommand(
			test::toolPath("keygrid-sim") + " --quiet --frames 300 --scene " + test::sourceDir() +
				"/config/sim/room_loop.ini --output " + dir + "/seq",
			&log),
		0)
		<< log;
	// Frames 0..149 (half of the circle), then frames 20..59 again: the start of the loop.
	const auto assoc = core::readTumTextRecords(dir + "/seq/tum/associations.txt");
	const auto gt = core::readTumTrajectory(dir + "/seq/groundtruth.txt");
	ASSERT_EQ(assoc.size(), 300u);
	ASSERT_EQ(gt.size(), 300u);
	std::vector<int> order;
	for (int i = 0; i < 150; i++) order.push_back(i);
	const std::size_t kidnap = order.size();
	for (int i = 20; i < 60; i++) order.push_back(i);
	mrpt::system::createDirectory(dir + "/kidnapped");
	core::Trajectory kidnappedGt;
	{
		std::ofstream a(dir + "/kidnapped/associations.txt");
		for (std::size_t k = 0; k < order.size(); k++)
		{
			char t[32];
			std::snprintf(t, sizeof(t), "%.6f", 1700000000.0 + k / 30.0);
			const auto& f = assoc[order[k]].fields;
			a << t << " ../seq/tum/" << f.at(1) << " " << t << " ../seq/tum/" << f.at(3) << "\n";
			kidnappedGt.push_back({std::stod(t), gt[order[k]].T_world_cam});
		}
	}
	core::writeTumTrajectory(dir + "/kidnapped/groundtruth.txt", kidnappedGt);

	const auto o = test::shippedConfigRun("config/sim.ini", dir + "/kidnapped", dir + "/out");
	const auto r = slam::runSlam(o);
	EXPECT_TRUE(r.error.empty()) << r.error;
	ASSERT_EQ(r.frames, order.size());
	const std::string js = test::readTextFile(o.output + "/report.json");
	// The first relocalization: right after the jump, on a keyframe proposed by the vocabulary.
	const auto events = nlohmann::json::parse(js)["relocalization_events"];
	ASSERT_FALSE(events.empty()) << js;
	EXPECT_LE(events[0]["frame"].get<std::size_t>(), kidnap + 2);
	EXPECT_TRUE(events[0]["place_recognition"].get<bool>());
	// Empirical margin: the jump's frame and two more may be lost (frames lost after the jump:
	// doc/evaluation.md, "Relocalization").
	EXPECT_GE(r.tracked, order.size() - 3);

	// Align on the frames before the jump, then every frame from 3 after it must be at its
	// true pose: 2 cm, an empirical margin over the error after the jump in doc/evaluation.md,
	// "Relocalization".
	const auto est = core::readTumTrajectory(o.output + "/trajectory.txt");
	const auto& ref = kidnappedGt;
	ASSERT_EQ(est.size(), order.size());
	ASSERT_EQ(ref.size(), order.size());
	std::vector<Eigen::Vector3d> x, y;
	for (std::size_t k = 0; k < kidnap; k++)
	{
		x.push_back(sfm::translationOf(est[k].T_world_cam));
		y.push_back(sfm::translationOf(ref[k].T_world_cam));
	}
	const auto S = eval::alignPointSets(x, y, false);
	double worst = 0;
	for (std::size_t k = kidnap + 3; k < order.size(); k++)
		worst = std::max(worst, (S.apply(sfm::translationOf(est[k].T_world_cam)) - sfm::translationOf(ref[k].T_world_cam)).norm());
	EXPECT_LT(worst, 0.02);
}

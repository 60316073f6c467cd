// Augment mode: objects rendered into an existing TUM sequence with occlusion against its
// depth must look exactly like rendering the objects together with the original scene.
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/Augment.h>
#include <keygrid/sim/SequenceWriter.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "SimTestScenes.h"
#include "TestData.h"

#include <filesystem>

using namespace keygrid;

namespace
{
const char* kHeader = "[scene]\nname = aug\nseed = 8\nframes = 4\n";
// Exact depth everywhere (no grazing-angle holes): where the real depth is invalid the
// augmenter cannot know about occluders and draws the object, by design.
const char* kNoNoise = "[sensor]\nnoise = false\nmax_incidence_deg = 90\nmax_range = 13\n";
// The "real" world: a corner of a room with a box; the camera pans.
const char* kBase =
	"[trajectory]\nwp_00 = 0.5 0.5 1.2  3 1.2 0.9\nwp_01 = 0.6 0.7 1.2  3 2.2 0.9\n"
	"[object.floor]\ntype = quad\ncorner = -2 -2 0\nedge1 = 8 0 0\nedge2 = 0 8 0\n"
	"[object.wall]\ntype = quad\ncorner = 3.5 -2 0\nedge1 = 0 8 0\nedge2 = 0 0 3\n"
	"[object.box]\ntype = box\ncentre = 2.0 1.5 0.4\nsize = 0.6 0.6 0.8\nyaw = 10\n";
// Inserted: a cylinder passing behind the box and in front of the wall.
const char* kObjects =
	"[object.visitor]\ntype = cylinder\ncentre = 2.6 0.5 0.7\nradius = 0.2\nheight = 1.4\n"
	"dynamic = true\npath_00 = 0 2.6 1.0 0.7\npath_01 = 1.0 2.6 3.4 0.7\n";

std::vector<std::string> sortedFiles(const std::string& dir)
{
	std::vector<std::string> out;
	for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path().string());
	std::sort(out.begin(), out.end());
	return out;
}
}  // namespace

TEST(Augment, MatchesRenderingTheObjectsWithTheScene)
{
	sim::OutputOptions o;
	o.writeMask = true;
	const std::string real = test::scratchDir("sim_aug_real"),
					  aug = test::scratchDir("sim_aug_out"),
					  both = test::scratchDir("sim_aug_both");
	const std::string cam = test::tinyCameraIni();
	sim::writeSequence(
		test::sceneFromString(std::string(kHeader) + cam + kNoNoise + kBase), real, o, {}, 2);
	const sim::Scene objects = test::sceneFromString(std::string(kHeader) + kNoNoise + kObjects);
	EXPECT_TRUE(objects.trajectory.empty());
	const sim::AugmentSummary s =
		sim::augmentTumSequence(objects, real + "/tum", aug, o, {}, {}, 2);
	EXPECT_EQ(s.frames, 4u);
	EXPECT_EQ(s.skippedNoPose, 0u);
	EXPECT_GT(s.insertedPixelFraction, 0.01);
	sim::writeSequence(
		test::sceneFromString(std::string(kHeader) + cam + kNoNoise + kBase + kObjects), both, o,
		{}, 2);

	for (const char* sub : {"depth", "rgb", "mask"})
	{
		const auto a = sortedFiles(aug + "/tum/" + sub), b = sortedFiles(both + "/tum/" + sub);
		ASSERT_EQ(a.size(), 4u) << sub;
		ASSERT_EQ(b.size(), 4u) << sub;
		for (std::size_t i = 0; i < 4; i++)
		{
			const cv::Mat ia = cv::imread(a[i], cv::IMREAD_UNCHANGED),
						  ib = cv::imread(b[i], cv::IMREAD_UNCHANGED);
			ASSERT_EQ(ia.size(), ib.size());
			cv::Mat absDiff, big;
			cv::absdiff(ia.reshape(1), ib.reshape(1), absDiff);
			// Object time comes from timestamps printed with 6 decimals (<= 0.5 us off, the
			// object moves 2.4 m/s: ~1 um): depth may move by one raw step (0.2 mm) and colour
			// by a few levels; anything beyond that on more than a handful of boundary pixels
			// is a real disagreement.
			const double tol = std::string(sub) == "depth" ? 1 : std::string(sub) == "rgb" ? 8 : 0;
			cv::compare(absDiff, tol, big, cv::CMP_GT);
			EXPECT_LE(cv::countNonZero(big), 4) << sub << " frame " << i;
		}
	}
	// Augmented frames carry the input's poses.
	const auto gtIn = core::readTumTrajectory(real + "/groundtruth.txt");
	const auto gtOut = core::readTumTrajectory(aug + "/groundtruth.txt");
	ASSERT_EQ(gtOut.size(), gtIn.size());
	for (std::size_t i = 0; i < gtIn.size(); i++)
		EXPECT_NEAR((gtIn[i].T_world_cam - gtOut[i].T_world_cam).translation().norm(), 0.0, 1e-9);
}

TEST(Augment, RealTumSequenceWithDistortedCamera)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_rpy_first250");
	const sim::Scene objects =
		sim::Scene::loadFromFile(test::sourceDir() + "/config/sim/augment_fr1_rpy.ini");
	sim::OutputOptions o;
	o.writeTum = false;
	sim::AugmentOptions ao;
	ao.maxFrames = 3;
	const std::string out = test::scratchDir("sim_aug_fr1");
	const auto s = sim::augmentTumSequence(
		objects, test::sharedDataDir() + "/tum_fr1_rpy_first250", out, o, ao, {}, 2);
	EXPECT_EQ(s.frames, 3u);
	EXPECT_GT(s.insertedPixelFraction, 0.005);  // the parcel is in view from the start
	core::RawlogFrameSource src(out + "/sequence.rawlog");
	core::Frame f;
	ASSERT_TRUE(src.next(f));
	EXPECT_NEAR(f.camera.dist[0], 0.262383, 1e-6);  // fr1 camera kept, with its distortion
}

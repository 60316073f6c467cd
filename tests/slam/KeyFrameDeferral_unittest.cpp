// Threaded mode's keyframe deferral (Tracker::deferKeyFramesWhile, [slam] / [monocular] busy_keyframe_ratio),
// made deterministic: the tracker and local mapping run in turn on a rendered sequence while
// the "mapping busy" answer is fixed. Never busy: exactly the keyframes of the plain tracker.
// Always busy: keyframes only where tracking is weak or, when no frame counts as weak, at the
// [tracker] max_frames_between_keyframes timeout.
#include <keygrid/core/FrameSource.h>
#include <keygrid/sfm/FeatureExtractor.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/SlamConfig.h>
#include <mrpt/config/CConfigFileMemory.h>

#include "TestData.h"

#include <algorithm>
#include <functional>
#include <optional>

using namespace keygrid;

namespace
{
/** Frame indices that became keyframes, and the number of frames tracked (of those given to
 * the tracker: every `stride`-th frame, at most maxFrames). */
struct Run
{
	std::vector<std::size_t> keyframeFrames;
	/** Per keyframe: inserted while mapping was busy (TrackedFrame::keyFrameWhileMappingBusy). */
	std::vector<bool> whileBusy;
	std::size_t tracked{0}, frames{0};
};

Run track(const std::string& tumDir, const std::optional<std::pair<std::function<bool()>, double>>& deferral, std::size_t maxFrames, std::size_t stride = 1)
{
	const auto cfg = slam::SlamConfig::FromFile(test::sourceDir() + "/config/sim.ini");
	sfm::SparseMap map;
	sfm::Tracker tracker(map, cfg.tracker);
	if (deferral) tracker.deferKeyFramesWhile(deferral->first, deferral->second);
	sfm::LocalMapper mapper(map, cfg.mapping, cfg.tracker.matcher);
	const sfm::FeatureExtractor extractor(cfg.features);
	auto source = core::openFrameSource(tumDir);
	Run run;
	core::Frame frame;
	for (std::size_t i = 0; run.frames < maxFrames && source->next(frame); i++)
	{
		if (i % stride) continue;
		const auto tf = tracker.track(frame, extractor.extract(frame));
		run.frames++;
		run.tracked += tf.tracked;
		if (tf.newKeyFrame)
		{
			run.keyframeFrames.push_back(tf.index);
			run.whileBusy.push_back(tf.keyFrameWhileMappingBusy);
			mapper.process(tf.keyframe, frame.camera.pinhole());
		}
	}
	return run;
}
}  // namespace

TEST(KeyFrameDeferral, BusyMappingDefersKeyFramesToWeakTrackingOrTheTimeout)
{
	// room_arc over 200 frames (slow enough that one keyframe's map holds for 30 frames); the
	// first 100 are tracked.
	const std::string dir = test::scratchDir("keyframe_deferral");
	std::string log;
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-sim") + " --quiet --scene " + test::dataDir() +
								   "/sim/room_arc.ini --frames 200 --voxel-resolution 0 --floorplan-resolution 0 --output " + dir,
							   &log),
			  0)
		<< log;
	using Deferral = std::pair<std::function<bool()>, double>;
	const auto plain = track(dir + "/tum", std::nullopt, 100);
	ASSERT_EQ(plain.tracked, 100u);
	ASSERT_GT(plain.keyframeFrames.size(), 6u);

	int asked = 0;
	const auto idle = track(dir + "/tum", Deferral([&] { return ++asked, false; }, 0.25), 100);
	EXPECT_EQ(idle.keyframeFrames, plain.keyframeFrames);
	EXPECT_GT(asked, 0);  // consulted, never deferring
	EXPECT_EQ(std::count(idle.whileBusy.begin(), idle.whileBusy.end(), true), 0);

	// Busy, and no frame tracks below 1 % of its reference: only the timeout (config/sim.ini
	// keeps the default of 30 frames) inserts keyframes.
	const auto timeoutOnly = track(dir + "/tum", Deferral([] { return true; }, 0.01), 100);
	EXPECT_EQ(timeoutOnly.tracked, 100u);
	EXPECT_EQ(timeoutOnly.keyframeFrames, (std::vector<std::size_t>{0, 30, 60, 90}));

	// Three times the motion per frame (every third frame): the timeout alone would come too
	// late, but with the default share weak tracking still inserts keyframes, and every frame
	// is tracked with fewer keyframes than without deferral.
	const auto fastPlain = track(dir + "/tum", std::nullopt, 66, 3);
	const auto fastBusy = track(dir + "/tum", Deferral([] { return true; }, 0.25), 66, 3);
	EXPECT_EQ(fastBusy.tracked, 66u);
	EXPECT_LT(fastBusy.keyframeFrames.size(), fastPlain.keyframeFrames.size());
	// A keyframe before the timeout was inserted despite the busy mapping (tracking weak) and
	// says so; one at the timeout does not.
	bool beforeTimeout = false;
	for (std::size_t k = 1; k < fastBusy.keyframeFrames.size(); k++)
	{
		const bool early = fastBusy.keyframeFrames[k] - fastBusy.keyframeFrames[k - 1] < 30;  // frame indices: the timeout counts them
		beforeTimeout |= early;
		EXPECT_EQ(fastBusy.whileBusy[k], early) << "keyframe at frame " << fastBusy.keyframeFrames[k];
	}
	EXPECT_TRUE(beforeTimeout);
	EXPECT_FALSE(fastBusy.whileBusy.front());  // the map's first keyframe
}

TEST(KeyFrameDeferral, MonocularModeDefersWithItsOwnShare)
{
	// The share comes from [monocular] in monocular mode, from [slam] otherwise, and only
	// threaded mode with a mapping lag defers at all.
	const auto config = [](const std::string& slamKeys)
	{
		mrpt::config::CConfigFileMemory ini("[slam]\n" + slamKeys + "\nbusy_keyframe_ratio = 0.3\n[monocular]\nbusy_keyframe_ratio = 0.7\n");
		return slam::SlamConfig::FromConfig(ini, "test");
	};
	EXPECT_DOUBLE_EQ(config("mode = threaded\nsensor = monocular").deferralRatio(), 0.7);
	EXPECT_DOUBLE_EQ(config("mode = threaded\nsensor = rgbd").deferralRatio(), 0.3);
	EXPECT_DOUBLE_EQ(config("mode = threaded\nsensor = monocular\nmapping_lag = 0").deferralRatio(), 0.0);
	EXPECT_DOUBLE_EQ(config("mode = sequential\nsensor = monocular").deferralRatio(), 0.0);
	// The defaults: 0.6 for a monocular camera, 0.35 for RGB-D.
	mrpt::config::CConfigFileMemory mono("[slam]\nmode = threaded\nsensor = monocular\n");
	EXPECT_DOUBLE_EQ(slam::SlamConfig::FromConfig(mono, "test").deferralRatio(), 0.6);
	mrpt::config::CConfigFileMemory rgbd("[slam]\nmode = threaded\n");
	EXPECT_DOUBLE_EQ(slam::SlamConfig::FromConfig(rgbd, "test").deferralRatio(), 0.35);
}

TEST(KeyFrameDeferral, WaitingAfterAWeakKeyFrameIsReadPerSensor)
{
	// [monocular] wait_for_weak_keyframes in monocular mode, [slam] otherwise; never where no
	// keyframe is deferred (sequential mode, mapping_lag 0, a share of 0).
	const auto config = [](const std::string& slamKeys)
	{
		mrpt::config::CConfigFileMemory ini("[slam]\n" + slamKeys + "\nwait_for_weak_keyframes = true\n[monocular]\nwait_for_weak_keyframes = false\n");
		return slam::SlamConfig::FromConfig(ini, "test");
	};
	EXPECT_FALSE(config("mode = threaded\nsensor = monocular").waitsForWeakKeyFrames());
	EXPECT_TRUE(config("mode = threaded\nsensor = rgbd").waitsForWeakKeyFrames());
	EXPECT_FALSE(config("mode = threaded\nsensor = rgbd\nmapping_lag = 0").waitsForWeakKeyFrames());
	EXPECT_FALSE(config("mode = threaded\nsensor = rgbd\nbusy_keyframe_ratio = 0").waitsForWeakKeyFrames());
	EXPECT_FALSE(config("mode = sequential\nsensor = rgbd").waitsForWeakKeyFrames());
	// The defaults: on for a monocular camera, off for RGB-D (whose rule is unchanged).
	mrpt::config::CConfigFileMemory mono("[slam]\nmode = threaded\nsensor = monocular\n");
	EXPECT_TRUE(slam::SlamConfig::FromConfig(mono, "test").waitsForWeakKeyFrames());
	mrpt::config::CConfigFileMemory rgbd("[slam]\nmode = threaded\n");
	EXPECT_FALSE(slam::SlamConfig::FromConfig(rgbd, "test").waitsForWeakKeyFrames());
}

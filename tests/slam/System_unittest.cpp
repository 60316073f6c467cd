// slam::System driven directly (sequential mode), frame by frame as keygrid-slam feeds it, with
// synthetic features of known 3D points seen from known camera poses (SyntheticFeatures.h): a
// camera on a small circle inside a textured cylinder, looking out at its wall. Standing
// still, then turning: every frame tracked, keyframes only once it turns, every pose within a
// bound derived from the measurement noise, online and after finish(). Turning past one full
// circle: the loop closes, and its correction reaches the map, the tracker's frame and the
// metric maps (a 2D grid fed with the keyframes' map points).
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/slam/System.h>
#include <mrpt/config/CConfigFileMemory.h>

#include "SyntheticFeatures.h"
#include "TestData.h"

#include <cmath>
#include <map>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
/** The wall: a cylinder about the vertical (camera y, pointing down) axis [m], closer than
 * [tracker] close_depth from anywhere on the camera's circle, so that every point a keyframe
 * sees becomes a landmark. */
constexpr double kWallRadius = 2.5, kWallHalfHeight = 1.0;
constexpr int kWallPoints = 5000;
/** The camera's circle [m] and heading step per frame while turning [deg]. */
constexpr double kPathRadius = 0.5, kHeadingStepDeg = 4.0;
/** The farthest a camera on the circle sees the wall [m]. */
constexpr double kMaxDepth = kWallRadius + kPathRadius;

test::SyntheticPoints makeWall(std::mt19937& rng) { return test::cylinderWall(rng, kWallRadius, kWallHalfHeight, kWallPoints); }

/** The camera after `steps` heading steps: on the circle, looking outwards (optical axis =
 * radial direction), its radius and tilt wobbling a little (a pure turn about one axis would
 * make every pair of poses commute and hide composition-order mistakes). The first camera
 * defines the world frame: the ground truth is relative to it. */
CPose3D circlePose(int steps)
{
	const double heading = kHeadingStepDeg * steps * M_PI / 180.0;
	const double radius = kPathRadius + 0.05 * std::sin(3 * heading), tilt = 3.0 * M_PI / 180.0 * std::sin(2 * heading);
	return CPose3D(radius * std::sin(heading), 0, radius * std::cos(heading), 0, heading, tilt);
}

CPose3D turnedPose(int steps) { return circlePose(steps) - circlePose(0); }

/** Sequential mode, the loop closer's vocabulary trained on the run's first keyframes. */
slam::SlamConfig sequentialConfig()
{
	slam::SlamConfig cfg;
	cfg.mode = slam::RunMode::Sequential;
	cfg.loop.vocabulary = "train";
	return cfg;
}

/** Pose error of `estimate` against `truth`: translation [m] and rotation [deg]. */
test::AlignmentSigmas poseError(const CPose3D& estimate, const CPose3D& truth)
{
	const CPose3D e = estimate - truth;
	return {e.translation().norm(), test::rotationAngleDeg(e)};
}

/** The landmarks a frame's pose rests on (its inliers), in its true camera frame. */
std::vector<Eigen::Vector3d> inliers_cam(const slam::System& sys, const sfm::TrackedFrame& tf, const CPose3D& T_world_cam_true)
{
	std::vector<Eigen::Vector3d> out;
	for (const auto l : tf.observedLandmarks)
	{
		if (!sys.map().hasLandmark(l)) continue;
		const Eigen::Vector3d& p = sys.map().landmark(l).p_world;
		Eigen::Vector3d q;
		T_world_cam_true.inverseComposePoint(p.x(), p.y(), p.z(), q.x(), q.y(), q.z());
		out.push_back(q);
	}
	return out;
}

// ---------------------------------------------------------------- still, then turning
/** Frames standing at the first pose (fewer than [tracker] max_frames_between_keyframes), then
 * frames turning by kHeadingStepDeg each. */
constexpr int kStillFrames = 10, kTurningFrames = 40;

struct TurnRun
{
	std::vector<CPose3D> truth;
	std::vector<test::AlignmentSigmas> bound;  //!< per frame, see runTurn()
};

/** Feeds the frames to `sys`, checking that each is tracked and that no keyframe is made
 * while the camera stands still; returns the ground truth and each frame's error bound. */
TurnRun runTurn(slam::System& sys, const test::MeasurementNoise& noise, double sigmas, unsigned seed)
{
	std::mt19937 rng(seed);
	const auto wall = makeWall(rng);
	const core::RgbdCamera cam;
	// Each pose rests on landmarks measured once and on the frame's own measurements, each with
	// a point error of noise.pointSigma: sqrt(2) times that per point, so one step (a frame
	// against the landmarks of one keyframe) has the standard deviations of a rigid alignment
	// of the frame's inliers; `sigmas` of those bound it. The landmarks of each keyframe carry
	// that keyframe's pose error, so over a chain of k keyframes the errors of k steps add up:
	// at most k times one step's bound.
	const double pointSigma = std::sqrt(2.0) * noise.pointSigma(kMaxDepth, cam.fx);
	TurnRun run;
	int keyframes = 0;  // made before the current frame
	for (int i = 0; i < kStillFrames + kTurningFrames; i++)
	{
		const CPose3D T_world_cam = turnedPose(std::max(0, i - kStillFrames + 1));
		const auto& tf = sys.processExtracted(test::blankFrame(static_cast<std::size_t>(i), cam), test::observePoints(wall, T_world_cam, cam, noise, rng));
		EXPECT_TRUE(tf.tracked) << "frame " << i;
		if (i < kStillFrames)
		{
			EXPECT_EQ(tf.newKeyFrame, i == 0) << "frame " << i;
		}
		if (i == 0)
		{
			// The first camera defines the world frame, as the ground truth does.
			run.truth.push_back(T_world_cam);
			run.bound.push_back({1e-12, 1e-9});
			keyframes++;
			continue;
		}
		const auto inliers = inliers_cam(sys, tf, T_world_cam);
		if (inliers.empty())
		{
			ADD_FAILURE() << "frame " << i << " rests on no landmark";
			return run;
		}
		const auto sigma = test::alignmentSigmas(inliers, pointSigma, static_cast<double>(inliers.size()));
		const double chain = keyframes;
		run.truth.push_back(T_world_cam);
		run.bound.push_back({sigmas * chain * sigma.metres, sigmas * chain * sigma.degrees});
		keyframes += tf.newKeyFrame;
	}
	EXPECT_EQ(sys.stats().tracked, run.truth.size());
	return run;
}

void expectWithinBound(const core::Trajectory& est, const TurnRun& run, const char* what)
{
	ASSERT_EQ(est.size(), run.truth.size()) << what;
	for (std::size_t i = 0; i < est.size(); i++)
	{
		const auto e = poseError(est[i].T_world_cam, run.truth[i]);
		EXPECT_LT(e.metres, run.bound[i].metres) << what << ", frame " << i << ": " << est[i].T_world_cam << " vs " << run.truth[i];
		EXPECT_LT(e.degrees, run.bound[i].degrees) << what << ", frame " << i << ": " << est[i].T_world_cam << " vs " << run.truth[i];
	}
}
}  // namespace

TEST(System, TracksEveryFrameAndMakesKeyFramesWhenTheCameraTurns)
{
	// finish(): the global bundle adjustment, the frames following their reference keyframes
	// (the frames' own re-estimation is not part of this bound).
	auto cfg = sequentialConfig();
	cfg.refinement.refineFrames = false;
	slam::System sys(cfg);
	const auto run = runTurn(sys, test::MeasurementNoise{0.5, 0.005}, 6.0, 1);
	// Turning makes keyframes before the timeout would: at least one per field of view turned
	// (beyond that, nothing the last keyframe saw would be in view).
	const double fovDeg = 2 * std::atan2(0.5 * core::RgbdCamera().width, core::RgbdCamera().fx) * 180.0 / M_PI;
	int turningKeyFrames = 0;
	for (const auto& f : sys.frames()) turningKeyFrames += f.newKeyFrame && f.index >= static_cast<std::size_t>(kStillFrames);
	EXPECT_GE(turningKeyFrames, static_cast<int>(kTurningFrames * kHeadingStepDeg / fovDeg));
	EXPECT_GT(turningKeyFrames, kTurningFrames / cfg.tracker.maxFramesBetweenKeyFrames);
	expectWithinBound(sys.trajectory(), run, "online");
	sys.finish();
	expectWithinBound(sys.trajectory(), run, "after finish()");
}

namespace
{
// ---------------------------------------------------------------- a loop
/** A keyframe every kFramesPerKeyFrame frames ([tracker] max_frames_between_keyframes): about
 * thirty a turn, so that the last turn's keyframes are more than [loop] min_keyframe_gap after
 * the first ones; frames past one full turn, so that they see the first keyframes' wall. */
constexpr int kFramesPerKeyFrame = 3, kLoopFrames = 112;

/** The keyframe poses the 2D grid holds. */
std::map<sfm::KeyFrameId, CPose3D> gridPoses(const slam::System& sys)
{
	std::map<sfm::KeyFrameId, CPose3D> out;
	for (const auto& [id, kf] : sys.metricMaps()->maps().mapByClass<CISMOccupancyGrid2D>()->keyframes()) out[id] = kf.T_world_cam;
	return out;
}

/** Same numbers (copies of one pose). */
bool samePose(const CPose3D& a, const CPose3D& b)
{
	return a.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>().asEigen() == b.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>().asEigen();
}

/** What the loop closure of frame `tf` published: the map's correction count, the
 * keyframes' corrected poses in the map and in the 2D grid, the frame at its keyframe's
 * corrected pose. `before`: the grid's poses before the frame. */
void expectCorrectionPublished(const slam::System& sys, const sfm::TrackedFrame& tf, const std::map<sfm::KeyFrameId, CPose3D>& before)
{
	const auto& ev = sys.loopClosures().back();
	EXPECT_TRUE(tf.newKeyFrame);
	EXPECT_EQ(ev.keyframe, tf.keyframe);
	EXPECT_EQ(ev.frameIndex, tf.index);
	EXPECT_EQ(sys.map().corrections(), sys.loopClosures().size());
	ASSERT_TRUE(ev.newPoses.count(ev.keyframe));
	EXPECT_TRUE(samePose(tf.T_world_cam, ev.newPoses.at(ev.keyframe))) << tf.T_world_cam << " vs " << ev.newPoses.at(ev.keyframe);
	const auto grid = gridPoses(sys);
	double moved = 0;
	for (const auto& [id, T] : ev.newPoses)
	{
		if (!sys.map().hasKeyFrame(id)) continue;
		EXPECT_TRUE(samePose(sys.map().keyframe(id).T_world_cam, T)) << "keyframe " << id;
		ASSERT_TRUE(grid.count(id)) << "keyframe " << id;
		EXPECT_TRUE(samePose(grid.at(id), T)) << "keyframe " << id << " in the grid: " << grid.at(id) << " vs " << T;
		if (before.count(id)) moved = std::max(moved, poseError(grid.at(id), before.at(id)).metres);
	}
	// The correction moved the keyframes the grid held.
	EXPECT_GT(moved, 0.0);
}
}  // namespace

TEST(System, ALoopClosurePublishesItsCorrectionToTheMapTheTrackerAndTheMetricMaps)
{
	auto cfg = sequentialConfig();
	cfg.tracker.maxFramesBetweenKeyFrames = kFramesPerKeyFrame;
	slam::System sys(cfg);
	// A 2D grid fed with the keyframes' map points, on a given floor (z up) at the wall's foot,
	// world y (down) = kWallHalfHeight.
	mrpt::config::CConfigFileMemory ini("[MappingApplication]\nismOccupancyGrid2D_count = 1\n");
	maps::FloorFrameOptions floor;
	floor.givenPose = "[0 " + std::to_string(kWallHalfHeight) + " 0 0 0 90]";
	sys.attachMaps(std::make_unique<slam::MetricMaps>(ini, cfg.maps, floor));

	std::mt19937 rng(3);
	const auto wall = makeWall(rng);
	const core::RgbdCamera cam;
	const test::MeasurementNoise noise{0.5, 0.01};
	for (int i = 0; i < kLoopFrames; i++)
	{
		const auto before = gridPoses(sys);
		const std::size_t loops = sys.loopClosures().size();
		const auto& tf = sys.processExtracted(test::blankFrame(static_cast<std::size_t>(i), cam), test::observePoints(wall, turnedPose(i), cam, noise, rng));
		EXPECT_TRUE(tf.tracked) << "frame " << i;
		if (sys.loopClosures().size() == loops) continue;
		SCOPED_TRACE("loop closed at frame " + std::to_string(i));
		expectCorrectionPublished(sys, tf, before);
	}
	ASSERT_FALSE(sys.loopClosures().empty());
	// Closed between two keyframes whose views overlap: one of the last turn, one of the first,
	// less than a field of view apart in heading.
	const double fovDeg = 2 * std::atan2(0.5 * cam.width, cam.fx) * 180.0 / M_PI;
	const auto& first = sys.loopClosures().front();
	const auto headingDeg = [&](double timestamp) { return std::round((timestamp - test::blankFrame(0, cam).timestamp) * 30.0) * kHeadingStepDeg; };
	EXPECT_LT(std::abs(360.0 + headingDeg(first.loopKeyFrameTimestamp) - headingDeg(first.keyframeTimestamp)), fovDeg);
}

// Tracker on synthetic features with known poses (SyntheticFeatures.h): a random point cloud is
// observed from ground-truth camera poses; the first frame starts the map (its camera defines
// the world frame), the next ones are tracked and their recovered poses are compared with the
// ground truth: exactly without measurement noise, within a bound derived from the noise with it.
#include <keygrid/sfm/Tracker.h>

#include "SyntheticFeatures.h"
#include "TestData.h"

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
/** Depth range of the world's points as seen from the first camera [m] */
constexpr double kMinDepth = 1.5, kMaxDepth = 4.0;
/** Points of the world, and the inliers every tracked frame must have: the points stay in view
 * over the frames of groundTruthPose() but for those leaving the image's edges. */
constexpr int kWorldPoints = 800, kMinInliers = 500;
constexpr int kFrames = 10;

/** kWorldPoints points spread over the first camera's (the world frame's) image at depths in
 * [kMinDepth, kMaxDepth]. */
test::SyntheticPoints makeWorld(const core::RgbdCamera& cam, std::mt19937& rng)
{
	return test::pointsInView(cam, rng, kWorldPoints, 10, kMinDepth, kMaxDepth);
}

/** The camera of frame i on a smooth path from the identity: about 2 cm and 0.4 deg a frame. */
CPose3D groundTruthPose(int i)
{
	const double s = static_cast<double>(i);
	return CPose3D(0.02 * s, -0.006 * s, 0.01 * s, 0.006 * s, -0.004 * s, 0.003 * s);
}

/** Tracks the kFrames frames of groundTruthPose() and checks every pose against the ground
 * truth within `tol`, each frame with at least kMinInliers inliers. */
void trackAndCompare(const test::SyntheticPoints& world, const test::MeasurementNoise& noise, const test::AlignmentSigmas& tol, std::mt19937& rng)
{
	const core::RgbdCamera cam;
	sfm::SparseMap map;
	sfm::Tracker tracker(map, sfm::TrackerOptions());
	for (int i = 0; i < kFrames; i++)
	{
		const CPose3D T_world_cam = groundTruthPose(i);
		const sfm::TrackedFrame tf =
			tracker.track(test::blankFrame(static_cast<std::size_t>(i), cam), test::observePoints(world, T_world_cam, cam, noise, rng));
		ASSERT_TRUE(tf.tracked) << "frame " << i;
		// The second frame has no motion model yet: it is matched to the first keyframe by
		// descriptors (PnP); the later ones are searched around the motion model's prediction.
		const auto expectedMethod = i == 0 ? sfm::TrackingMethod::Init : i == 1 ? sfm::TrackingMethod::Pnp : sfm::TrackingMethod::Prediction;
		EXPECT_EQ(tf.method, expectedMethod) << "frame " << i;
		EXPECT_GE(tf.inliers, kMinInliers) << "frame " << i;
		// The world is the first camera's frame, and the ground truth starts at the identity.
		const CPose3D error = tf.T_world_cam - T_world_cam;
		EXPECT_LT(error.translation().norm(), tol.metres) << "frame " << i << ": " << tf.T_world_cam << " vs " << T_world_cam;
		EXPECT_LT(test::rotationAngleDeg(error), tol.degrees) << "frame " << i << ": " << tf.T_world_cam << " vs " << T_world_cam;
	}
	EXPECT_GE(map.numKeyFrames(), 1u);
}
}  // namespace

TEST(Tracker, ExactMeasurementsGiveTheGroundTruthPose)
{
	// Without noise the ground truth is a zero of the cost: what remains is the solver's
	// convergence and the float storage of keypoints and depths (1e-7 relative: below a
	// micrometre at 4 m, 1e-5 deg).
	const core::RgbdCamera cam;
	std::mt19937 rng(1);
	const auto world = makeWorld(cam, rng);
	trackAndCompare(world, test::MeasurementNoise{}, {1e-6, 1e-5}, rng);
}

TEST(Tracker, NoisyMeasurementsStayWithinTheirBound)
{
	// Each tracked pose rests on the landmarks (measured in the first frame) and the frame's own
	// measurements, each with a point error of noise.pointSigma: sqrt(2) times that per point.
	// The bound: six standard deviations of a rigid alignment of kMinInliers such points.
	const core::RgbdCamera cam;
	const test::MeasurementNoise noise{0.5, 0.005};
	const double pointSigma = std::sqrt(2.0) * noise.pointSigma(kMaxDepth, cam.fx);
	for (unsigned seed : {1u, 2u, 3u})
	{
		std::mt19937 rng(seed);
		const auto world = makeWorld(cam, rng);
		const auto sigma = test::alignmentSigmas(world.p_world, pointSigma, kMinInliers);
		trackAndCompare(world, noise, {6 * sigma.metres, 6 * sigma.degrees}, rng);
	}
}

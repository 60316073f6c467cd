// LoopCloser on its own, fed keyframes of a synthetic world with known poses (SyntheticFeatures.h):
// a camera turns on a small circle inside a textured cylinder, looking out at its wall. The
// keyframe poses carry a growing drift, as odometry would leave them; the measurements are
// those of the ground-truth poses. On a path past one full turn the loop must be closed between
// keyframes that see the same wall, its measured relative pose must agree with the ground truth
// within a bound derived from the noise, and the correction must take the map most of the way
// to the measurement. On a path that stops short of its start no loop may be claimed.
// Monocular: the keyframes also drift in scale (each keyframe's part of the map is a similarity
// of the truth) and carry no depth; the loop must be measured as a similarity and the
// correction must take the scale drift out. When the best-scoring candidate has lost its
// landmarks, the next consistent candidate must close the loop.
#include <keygrid/sfm/Tracker.h>
#include <keygrid/loop/LoopCloser.h>

#include "SyntheticFeatures.h"
#include "TestData.h"

#include <algorithm>
#include <cmath>
#include <map>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
/** The wall: a cylinder about the vertical (camera y, pointing down) axis [m]. */
constexpr double kWallRadius = 4.0, kWallHalfHeight = 1.5;
constexpr int kWallPoints = 4000;
/** The camera's circle [m], heading step between keyframes [deg] and rise per keyframe [m]. */
constexpr double kPathRadius = 0.5, kHeadingStepDeg = 10.5, kRisePerKeyFrame = 0.005;
/** Keyframes of a path past one full turn (the last ones see the first ones' wall again), and
 * of one whose last keyframe heads 87 deg short of the first: from the circle each camera sees
 * the wall within about 28 deg of its heading, so their views of the wall do not meet. */
constexpr int kKeyFramesWithLoop = 42, kKeyFramesWithoutLoop = 27;
/** The farthest a camera on the circle sees the wall: to the wall's far side at the image
 * corners, bounded by the wall's radius plus the circle's [m]. */
constexpr double kMaxDepth = kWallRadius + kPathRadius;
/** A landmark stays in the local map while one of the last kLocalMapKeyFrames keyframes
 * observes it; a point seen again after that gets a new landmark, as tracking would create one. */
constexpr sfm::KeyFrameId kLocalMapKeyFrames = 5;
/** Monocular: the scale of keyframe k's part of the map is e^(kScaleDriftPerKeyFrame k) map
 * units per metre (23 % at the last keyframe of the loop path). */
constexpr double kScaleDriftPerKeyFrame = 0.005;

enum class Sensor
{
	Rgbd,
	Monocular
};

test::SyntheticPoints makeWall(std::mt19937& rng) { return test::cylinderWall(rng, kWallRadius, kWallHalfHeight, kWallPoints); }

double headingDeg(std::size_t k) { return kHeadingStepDeg * static_cast<double>(k); }

/** Ground truth of keyframe k: on the circle, heading k steps about the vertical axis, looking
 * outwards (optical axis = radial direction), rising a little per keyframe. */
CPose3D groundTruthPose(std::size_t k)
{
	const double heading = headingDeg(k) * M_PI / 180.0;
	return CPose3D(kPathRadius * std::sin(heading), -kRisePerKeyFrame * static_cast<double>(k), kPathRadius * std::cos(heading), 0, heading, 0);
}

/** Odometry drift of keyframe k, applied in the world frame: 2 mm and 1 mm along x and z and
 * 0.046 deg about the vertical per keyframe. */
CPose3D drift(std::size_t k)
{
	const double s = static_cast<double>(k);
	return CPose3D(0.002 * s, 0, 0.001 * s, 0, 0.0008 * s, 0);
}

/** Monocular drift of keyframe k: drift(k) with the scale e^(kScaleDriftPerKeyFrame k). */
loop::Sim3 similarityDrift(std::size_t k)
{
	return loop::Sim3::fromIsometry(loop::toIsometry(drift(k)), std::exp(kScaleDriftPerKeyFrame * static_cast<double>(k)));
}

/** Keyframe k as the drifted map holds it: the map maps its camera coordinates (metres) to the
 * world by similarityDrift(k) * groundTruthPose(k); its pose is that similarity's rigid part. */
loop::Sim3 driftedSim3(std::size_t k) { return similarityDrift(k) * loop::Sim3::fromIsometry(loop::toIsometry(groundTruthPose(k))); }

/** The keyframes of one path put through the loop closer, as local mapping would leave them. */
class LoopRun
{
   public:
	explicit LoopRun(unsigned seed, Sensor sensor = Sensor::Rgbd)
		: m_sensor(sensor), m_rng(seed), m_wall(makeWall(m_rng)), m_mapper(m_map, {}, {}), m_loop(m_map, m_mapper, options(sensor), {})
	{
	}

	/** Adds keyframe k (drifted pose, measurements from the ground truth), then loop closing.
	 * Keyframes are added in path order, so keyframe ids are the path's keyframe numbers. */
	void addKeyFrame(std::size_t k)
	{
		sfm::KeyFrame kf;
		kf.frameIndex = 10 * k;
		kf.timestamp = 1.0 + static_cast<double>(k) / 3.0;
		kf.T_world_cam = m_sensor == Sensor::Rgbd ? drift(k) + groundTruthPose(k) : loop::toCPose3D(driftedSim3(k).rigid());
		std::vector<int> pointOf;
		kf.features = test::observePoints(m_wall, groundTruthPose(k), m_cam, m_noise, m_rng, &pointOf);
		const sfm::KeyFrameId id = m_map.addKeyFrame(std::move(kf)).id;
		associate(id, pointOf);
		// Without depth the keyframe has its landmarks only.
		if (m_sensor == Sensor::Monocular) std::fill(m_map.keyframe(id).features.depth.begin(), m_map.keyframe(id).features.depth.end(), 0.f);
		m_pointsOf[id] = std::move(pointOf);
		std::map<sfm::KeyFrameId, CPose3D> before;
		for (const auto& [kfId, keyframe] : m_map.keyframes()) before[kfId] = keyframe.T_world_cam;
		if (auto ev = m_loop.process(id, 10 * k, m_cam.pinhole()))
		{
			const auto& cur = m_map.keyframe(ev->keyframe);
			const auto& loop = m_map.keyframe(ev->loopKeyFrame);
			m_closures.push_back(
				{*ev, before.at(ev->keyframe) - before.at(ev->loopKeyFrame), cur.T_world_cam - loop.T_world_cam,
				 before.at(ev->keyframe) - before.at(0), cur.T_world_cam - m_map.keyframe(0).T_world_cam});
		}
	}

	/** A closed loop, and the current keyframe's pose relative to the loop keyframe and to the
	 * first keyframe in the map just before and just after the correction. */
	struct Closure
	{
		loop::LoopClosureEvent event;
		CPose3D T_loop_cur_before, T_loop_cur_after, T_first_cur_before, T_first_cur_after;
	};

	/** Takes every landmark off keyframe kf (its features stay, and so does its BoW entry), as
	 * culling and fusion can leave an old keyframe: verification against it finds no matches. */
	void eraseObservationsOf(sfm::KeyFrameId kf)
	{
		for (const auto l : std::vector<sfm::LandmarkId>(m_map.keyframe(kf).landmarks))
			if (l != sfm::kNoLandmark && m_map.hasLandmark(l)) m_map.eraseObservation(l, kf);
	}

	const loop::LoopCloser& loopCloser() const { return m_loop; }
	const std::vector<Closure>& closures() const { return m_closures; }
	const test::MeasurementNoise& noise() const { return m_noise; }

	/** The wall points both keyframes see, in keyframe a's ground-truth camera frame. */
	std::vector<Eigen::Vector3d> sharedPoints_cam(sfm::KeyFrameId a, sfm::KeyFrameId b) const
	{
		const CPose3D T_world_cam = groundTruthPose(a);
		const auto& seenByB = m_pointsOf.at(b);
		std::vector<Eigen::Vector3d> out;
		for (int j : m_pointsOf.at(a))
		{
			if (std::find(seenByB.begin(), seenByB.end(), j) == seenByB.end()) continue;
			Eigen::Vector3d p;
			T_world_cam.inverseComposePoint(m_wall.p_world[j].x(), m_wall.p_world[j].y(), m_wall.p_world[j].z(), p.x(), p.y(), p.z());
			out.push_back(p);
		}
		return out;
	}

   private:
	static loop::LoopClosingOptions options(Sensor sensor)
	{
		loop::LoopClosingOptions o;
		o.vocabulary = "train";  // on the first keyframes: no file needed
		o.monocular = sensor == Sensor::Monocular;
		return o;
	}

	/** Each keypoint observes the landmark of its wall point while that is in the local map,
	 * else a new landmark at its measured position (as the drifted pose places it). */
	void associate(sfm::KeyFrameId id, const std::vector<int>& pointOf)
	{
		const auto& kf = m_map.keyframe(id);
		const auto K = m_cam.pinhole();
		std::vector<sfm::LandmarkId> observed;
		for (std::size_t kp = 0; kp < pointOf.size(); kp++)
		{
			auto it = m_landmarkOfPoint.find(pointOf[kp]);
			// (A loop correction may have fused the landmark into another: then a new one.)
			if (it != m_landmarkOfPoint.end() && it->second.second + kLocalMapKeyFrames >= id && m_map.hasLandmark(it->second.first))
			{
				m_map.addObservation(it->second.first, id, static_cast<int>(kp));
				it->second.second = id;
				observed.push_back(it->second.first);
				continue;
			}
			const Eigen::Vector3d p_cam = K.backProject(kf.features.undistorted[kp].x, kf.features.undistorted[kp].y, kf.features.depth[kp]);
			Eigen::Vector3d p_world;
			kf.T_world_cam.composePoint(p_cam.x(), p_cam.y(), p_cam.z(), p_world.x(), p_world.y(), p_world.z());
			if (m_sensor == Sensor::Monocular) p_world = driftedSim3(id) * p_cam;  // in the keyframe's drifted scale
			m_landmarkOfPoint[pointOf[kp]] = {m_map.addLandmark(p_world, id, static_cast<int>(kp)), id};
		}
		for (auto l : observed) m_map.updateLandmarkStats(l);
		m_map.updateCovisibility(id);
	}

	Sensor m_sensor;
	std::mt19937 m_rng;
	const core::RgbdCamera m_cam;
	const test::MeasurementNoise m_noise{0.5, 0.01};
	test::SyntheticPoints m_wall;
	sfm::SparseMap m_map;
	sfm::LocalMapper m_mapper;
	loop::LoopCloser m_loop;
	/** wall point -> (its landmark, the last keyframe observing it) */
	std::map<int, std::pair<sfm::LandmarkId, sfm::KeyFrameId>> m_landmarkOfPoint;
	std::map<sfm::KeyFrameId, std::vector<int>> m_pointsOf;  //!< the wall points each keyframe sees
	std::vector<Closure> m_closures;
};

}  // namespace

TEST(LoopCloser, ClosesTheLoopBetweenKeyFramesOfTheSamePlaceWithTheGroundTruthPose)
{
	LoopRun run(1);
	for (std::size_t k = 0; k < kKeyFramesWithLoop; k++) run.addKeyFrame(k);
	ASSERT_FALSE(run.closures().empty());
	const int minInliers = loop::LoopClosingOptions().ransac.minInliers;
	const double pointSigma = std::sqrt(2.0) * run.noise().pointSigma(kMaxDepth, core::RgbdCamera().fx);
	for (const auto& c : run.closures())
	{
		const auto& ev = c.event;
		SCOPED_TRACE("loop " + std::to_string(ev.keyframe) + " -> " + std::to_string(ev.loopKeyFrame));
		// The right pair: the loop keyframe is an old one that sees enough of the current one's
		// wall to be verified, and at least half as much as the old keyframe that sees most of it.
		EXPECT_GE(ev.keyframe, ev.loopKeyFrame + static_cast<sfm::KeyFrameId>(loop::LoopClosingOptions().minKeyFrameGap));
		std::size_t mostShared = 0;
		for (sfm::KeyFrameId old = 0; old + static_cast<sfm::KeyFrameId>(loop::LoopClosingOptions().minKeyFrameGap) <= ev.keyframe; old++)
			mostShared = std::max(mostShared, run.sharedPoints_cam(old, ev.keyframe).size());
		const auto shared = run.sharedPoints_cam(ev.loopKeyFrame, ev.keyframe);
		EXPECT_GE(shared.size(), static_cast<std::size_t>(minInliers));
		EXPECT_GE(2 * shared.size(), mostShared);

		// The measurement against the ground truth: a rigid alignment of ev.inliers of the shared
		// points, each measured in both keyframes; six standard deviations.
		const CPose3D T_loop_cur_true = groundTruthPose(ev.keyframe) - groundTruthPose(ev.loopKeyFrame);
		const CPose3D measurementError = ev.T_loop_cur - T_loop_cur_true;
		const auto sigma = test::alignmentSigmas(shared, pointSigma, ev.inliers);
		EXPECT_GE(ev.inliers, minInliers);
		EXPECT_LT(measurementError.translation().norm(), 6 * sigma.metres) << ev.T_loop_cur << " vs " << T_loop_cur_true;
		EXPECT_LT(test::rotationAngleDeg(measurementError), 6 * sigma.degrees) << ev.T_loop_cur << " vs " << T_loop_cur_true;

		// The correction: the drift made the map disagree with the measurement by centimetres
		// and more than a degree. The pose graph (unit weights) shares that out between the
		// loop edge and the chain of odometry and covisibility edges joining the two keyframes;
		// one edge against many, the loop edge keeps less than half of it.
		const CPose3D before = c.T_loop_cur_before - ev.T_loop_cur, after = c.T_loop_cur_after - ev.T_loop_cur;
		EXPECT_GT(before.translation().norm(), 0.03);
		EXPECT_GT(test::rotationAngleDeg(before), 1.0);
		EXPECT_LT(after.translation().norm(), 0.5 * before.translation().norm()) << "before " << before << ", after " << after;
		EXPECT_LT(test::rotationAngleDeg(after), 0.5 * test::rotationAngleDeg(before)) << "before " << before << ", after " << after;
		// ... and brought the current keyframe closer to its true pose relative to the first.
		const CPose3D truth = groundTruthPose(ev.keyframe) - groundTruthPose(0);
		const CPose3D errorBefore = c.T_first_cur_before - truth, errorAfter = c.T_first_cur_after - truth;
		EXPECT_LT(errorAfter.translation().norm(), errorBefore.translation().norm()) << "before " << errorBefore << ", after " << errorAfter;
		EXPECT_LT(test::rotationAngleDeg(errorAfter), test::rotationAngleDeg(errorBefore)) << "before " << errorBefore << ", after " << errorAfter;
	}
	EXPECT_TRUE(run.loopCloser().lastPoseGraph().has_value());
}

TEST(LoopCloser, ClaimsNoLoopOnAPathWithoutRevisit)
{
	LoopRun run(2);
	for (std::size_t k = 0; k < kKeyFramesWithoutLoop; k++) run.addKeyFrame(k);
	EXPECT_TRUE(run.closures().empty());
	// Detection ran on every keyframe after the vocabulary was trained, and closed nothing.
	int queried = 0;
	for (const auto& q : run.loopCloser().queries())
	{
		EXPECT_NE(q.outcome, loop::LoopQueryOutcome::Closed) << "keyframe " << q.keyframe;
		queried += q.outcome != loop::LoopQueryOutcome::NoVocabulary;
	}
	// The keyframe that completes the training set trains the vocabulary and is not queried.
	EXPECT_EQ(queried, kKeyFramesWithoutLoop - loop::LoopClosingOptions().trainKeyFrames);
	EXPECT_FALSE(run.loopCloser().lastPoseGraph().has_value());
}

TEST(LoopCloser, MonocularLoopMeasuresTheScaleDriftAndCorrectsIt)
{
	LoopRun run(1, Sensor::Monocular);
	for (std::size_t k = 0; k < kKeyFramesWithLoop; k++) run.addKeyFrame(k);
	ASSERT_FALSE(run.closures().empty());
	for (const auto& q : run.loopCloser().queries())
		EXPECT_TRUE(q.outcome != loop::LoopQueryOutcome::Closed || q.projectedMatches >= loop::LoopClosingOptions().sim3MinMatches);
	const auto& c = run.closures().front();
	const auto& ev = c.event;
	SCOPED_TRACE("loop " + std::to_string(ev.keyframe) + " -> " + std::to_string(ev.loopKeyFrame));
	EXPECT_GE(ev.keyframe, ev.loopKeyFrame + static_cast<sfm::KeyFrameId>(loop::LoopClosingOptions().minKeyFrameGap));
	const double sCur = similarityDrift(ev.keyframe).s, sLoop = similarityDrift(ev.loopKeyFrame).s;

	// The measurement: the pose of the current camera in the loop keyframe's frame and units,
	// T_loop_cur_true with its translation in the loop keyframe's scale. The landmarks a
	// keyframe observes were placed by it or by one of the kLocalMapKeyFrames before it, so
	// each side's scale is uncertain by up to 5 x 0.5 % = 2.5 %; the rotation is fixed by the
	// pixels (0.5 px noise): well under a degree.
	const CPose3D T_loop_cur_true = groundTruthPose(ev.keyframe) - groundTruthPose(ev.loopKeyFrame);
	const CPose3D T_loop_cur_meas = ev.T_loop_cur;
	const Eigen::Vector3d t_true = sLoop * Eigen::Vector3d(T_loop_cur_true.x(), T_loop_cur_true.y(), T_loop_cur_true.z());
	const Eigen::Vector3d t_meas(T_loop_cur_meas.x(), T_loop_cur_meas.y(), T_loop_cur_meas.z());
	EXPECT_LT((t_meas - t_true).norm(), 0.05 * t_true.norm() + 0.01) << t_meas.transpose() << " vs " << t_true.transpose();
	EXPECT_LT(test::rotationAngleDeg(T_loop_cur_meas - T_loop_cur_true), 1.0);

	// The correction: before it the current keyframe's part of the map was sCur / sLoop times
	// the loop keyframe's (1.16). The Sim(3) pose graph (unit weights) shares that out between
	// the loop edge and the chain joining the two keyframes, whose covisibility edges (each
	// keyframe to the next kLocalMapKeyFrames) make it about as stiff as the one loop edge, as
	// in the rigid test above: at least half of the scale drift goes. A rigid correction would
	// leave scaleCorrection = 1 and fail this.
	const double driftBefore = std::log(sCur / sLoop);
	ASSERT_GT(driftBefore, 0.1);
	const double driftAfter = std::log(sCur * ev.scaleCorrection / sLoop);
	EXPECT_LT(std::abs(driftAfter), 0.5 * driftBefore) << "scale correction " << ev.scaleCorrection;
	// ... and the current keyframe lands closer to its true place relative to the first
	// keyframe, which the correction holds fixed, scale included (its units are the map's).
	const CPose3D truth = groundTruthPose(ev.keyframe) - groundTruthPose(0);
	const CPose3D errorBefore = c.T_first_cur_before - truth, errorAfter = c.T_first_cur_after - truth;
	EXPECT_LT(errorAfter.translation().norm(), 0.5 * errorBefore.translation().norm()) << "before " << errorBefore << ", after " << errorAfter;
	EXPECT_LT(test::rotationAngleDeg(errorAfter), test::rotationAngleDeg(errorBefore)) << "before " << errorBefore << ", after " << errorAfter;
	// The first keyframe holds the map's units: not moved.
	ASSERT_EQ(ev.newPoses.count(0), 1u);
	EXPECT_LT((ev.newPoses.at(0) - loop::toCPose3D(driftedSim3(0).rigid())).translation().norm(), 1e-9);
	// Each moved keyframe's scale goes out with its pose (for the maps): the fixed first one
	// keeps 1, the current one has the scale correction.
	ASSERT_EQ(ev.newScales.size(), ev.newPoses.size());
	for (const auto& [id, T] : ev.newPoses) EXPECT_EQ(ev.newScales.count(id), 1u) << "keyframe " << id;
	EXPECT_NEAR(ev.newScales.at(0), 1.0, 1e-12);
	EXPECT_DOUBLE_EQ(ev.newScales.at(ev.keyframe), ev.scaleCorrection);
}

TEST(LoopCloser, MonocularLoopIsVerifiedAgainstTheNextCandidateWhenTheBestHasNoLandmarks)
{
	// The loop as found on an intact map: the query keyframe that closes it and its loop keyframe.
	LoopRun intact(1, Sensor::Monocular);
	for (std::size_t k = 0; k < kKeyFramesWithLoop; k++) intact.addKeyFrame(k);
	ASSERT_FALSE(intact.closures().empty());
	const sfm::KeyFrameId closing = intact.closures().front().event.keyframe, loopKf = intact.closures().front().event.loopKeyFrame;
	const auto closedAt = [](const LoopRun& run, sfm::KeyFrameId kf)
	{
		for (const auto& q : run.loopCloser().queries())
			if (q.keyframe == kf) return q;
		return loop::LoopQueryRecord{};
	};
	EXPECT_EQ(closedAt(intact, closing).verifiedCount, 1) << "the best consistent candidate verified at once";

	// The same run with the loop keyframe's landmarks taken off once it has left the local map:
	// it still scores best in the database, but has nothing to match. The next consistent
	// candidate must close the loop, within a keyframe of the intact run (the next-best keyframe
	// may share too little of the view at the first query).
	LoopRun stripped(1, Sensor::Monocular);
	for (std::size_t k = 0; k < kKeyFramesWithLoop; k++)
	{
		stripped.addKeyFrame(k);
		if (k == loopKf + kLocalMapKeyFrames + 1) stripped.eraseObservationsOf(loopKf);
	}
	ASSERT_FALSE(stripped.closures().empty());
	const auto& ev = stripped.closures().front().event;
	EXPECT_LE(ev.keyframe, closing + 1);
	EXPECT_NE(ev.loopKeyFrame, loopKf);
	const auto q = closedAt(stripped, ev.keyframe);
	EXPECT_EQ(q.outcome, loop::LoopQueryOutcome::Closed);
	EXPECT_EQ(q.bestCandidate, loopKf);
	EXPECT_GE(q.verifiedCount, 2) << "the best candidate failed verification first";
	ASSERT_TRUE(q.verifiedCandidate.has_value());
	EXPECT_EQ(*q.verifiedCandidate, ev.loopKeyFrame);
	EXPECT_GE(q.projectedMatches, loop::LoopClosingOptions().sim3MinMatches);
	// The measurement is the true relative rotation (0.5 px noise: well under a degree).
	const CPose3D T_loop_cur_true = groundTruthPose(ev.keyframe) - groundTruthPose(ev.loopKeyFrame);
	EXPECT_LT(test::rotationAngleDeg(ev.T_loop_cur - T_loop_cur_true), 1.0);
}

// slam::MetricScale (monocular metric scale from camera_height) on a synthetic map in map units:
// keyframe cameras at height h_map above a floor of points, walls around. The first estimate
// scales the map by camera_height / h_map (closed form: exact floor, exact heights), and later
// estimates come every reestimate_every keyframes.
#include <keygrid/slam/MetricScale.h>

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <tuple>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
constexpr double kHeightMap = 0.5;  // camera height in map units
constexpr double kCameraHeight = 1.3;  // [m]

/** Optical frame (x right, y down, z forward) of a camera heading `yaw` about world z, pitched
 * down by 15 deg, at (x, y, h). */
CPose3D camera(double x, double y, double h, double yaw)
{
	const double pitch = 15 * M_PI / 180;
	const Eigen::Vector3d fwd(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch));
	const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0);
	mrpt::math::CMatrixDouble33 R;
	const Eigen::Vector3d down = fwd.cross(right);
	for (int i = 0; i < 3; i++)
	{
		R(i, 0) = right(i);
		R(i, 1) = down(i);
		R(i, 2) = fwd(i);
	}
	mrpt::math::CVectorFixedDouble<3> t;
	t[0] = x;
	t[1] = y;
	t[2] = h;
	return CPose3D::FromRotationAndTranslation(R, t);
}

sfm::KeyFrame keyFrame(const CPose3D& pose, int keypoints)
{
	sfm::KeyFrame kf;
	kf.T_world_cam = pose;
	kf.features.keypoints.resize(static_cast<std::size_t>(keypoints));
	kf.features.undistorted.resize(static_cast<std::size_t>(keypoints));
	kf.features.depth.assign(static_cast<std::size_t>(keypoints), 0.f);
	kf.features.descriptors = cv::Mat(keypoints, 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0};
	return kf;
}

/** Keyframe k on a circle of radius 0.4 map units around the room's centre, looking out. */
CPose3D circlePose(int k, double height)
{
	const double a = 0.3 * k;
	return camera(0.4 * std::cos(a), 0.4 * std::sin(a), height, a);
}

/** A room of 4 x 4 map units: floor points (z = 0) and wall points, observed by keyframe `kf`
 * and, as the frontend triangulates them, by keyframe `witness` from elsewhere (keypoints
 * from `firstKeypoint` on in both). */
void addRoom(sfm::SparseMap& map, sfm::KeyFrameId kf, sfm::KeyFrameId witness, int firstKeypoint = 0, double floorSlope = 0)
{
	std::mt19937 rng(5);
	// Walls start above the floor's inlier band: their feet would lift the fitted floor.
	std::uniform_real_distribution<double> u(-2, 2), h(0.1, 1.2);
	int kp = firstKeypoint;
	const auto add = [&](const Eigen::Vector3d& p)
	{
		map.addObservation(map.addLandmark(p, kf, kp), witness, kp);
		kp++;
	};
	for (int i = 0; i < 1500; i++)
	{
		const double x = u(rng);
		add({x, u(rng), floorSlope * x});
	}
	for (int i = 0; i < 1000; i++)
	{
		const double along = u(rng);
		const int wall = i % 4;
		add(wall == 0	? Eigen::Vector3d(2, along, h(rng))
			: wall == 1 ? Eigen::Vector3d(-2, along, h(rng))
			: wall == 2 ? Eigen::Vector3d(along, 2, h(rng))
						: Eigen::Vector3d(along, -2, h(rng)));
	}
}

slam::MetricScaleOptions options()
{
	slam::MetricScaleOptions o;
	o.estimator.cameraHeight = kCameraHeight;
	o.reestimateEvery = 10;
	return o;
}
}  // namespace

TEST(MetricScale, RescalesTheMapToTheCameraHeightAndReestimatesEveryNKeyFrames)
{
	sfm::SparseMap map;
	slam::MetricScale scale(options());
	const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2500)).id;
	// Fewer keyframes than min_keyframes (3): nothing is tried.
	addRoom(map, first, map.addKeyFrame(keyFrame(circlePose(6, kHeightMap), 2500)).id);
	EXPECT_FALSE(scale.update(map).has_value());
	EXPECT_EQ(scale.stats().estimates, 0);
	for (int k = 2; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
	const auto s = scale.update(map);
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	// Exact floor and heights: s = camera_height / h_map.
	EXPECT_NEAR(s->factor, kCameraHeight / kHeightMap, 1e-6 * kCameraHeight / kHeightMap) << scale.stats().lastMessage;
	EXPECT_TRUE(scale.metric());
	for (const auto& [id, kf] : map.keyframes()) EXPECT_NEAR(kf.T_world_cam.z(), kCameraHeight, 1e-5);
	EXPECT_NEAR(map.landmark(map.keyframe(first).landmarks[100]).p_world.z(), 0.0, 1e-12);  // a floor point stays on z = 0

	// Not due again before reestimate_every new keyframes; then the (now metric) map keeps
	// its scale.
	EXPECT_FALSE(scale.update(map).has_value());
	for (int k = 12; k < 21; k++) map.addKeyFrame(keyFrame(circlePose(k, kCameraHeight), 10));
	EXPECT_FALSE(scale.update(map).has_value());
	map.addKeyFrame(keyFrame(circlePose(21, kCameraHeight), 10));
	const auto again = scale.update(map);
	ASSERT_TRUE(again.has_value()) << scale.stats().lastMessage;
	EXPECT_NEAR(again->factor, 1.0, 1e-6);
	EXPECT_EQ(scale.stats().estimates, 2);
	EXPECT_EQ(scale.stats().applied, 2);
	EXPECT_NEAR(scale.stats().totalFactor, kCameraHeight / kHeightMap, 1e-5);
}

// After a Sim(3) loop correction (which keeps the first keyframe's units but rescales parts of
// the map) the scale is measured again at the next update, not reestimate_every keyframes later.
TEST(MetricScale, EstimatesAgainRightAfterARequest)
{
	sfm::SparseMap map;
	slam::MetricScale scale(options());
	const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2500)).id;
	addRoom(map, first, map.addKeyFrame(keyFrame(circlePose(6, kHeightMap), 2500)).id);
	for (int k = 1; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
	ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
	// The map grows by 10 % (as a correction could leave it): not due yet, unless requested.
	map.rescale(1.1);
	EXPECT_FALSE(scale.update(map).has_value());
	EXPECT_FALSE(scale.estimateRequested());
	scale.requestEstimate();
	EXPECT_TRUE(scale.estimateRequested());
	const auto s = scale.update(map);
	EXPECT_FALSE(scale.estimateRequested());
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	EXPECT_NEAR(s->factor, 1.0 / 1.1, 1e-6);
	for (const auto& [id, kf] : map.keyframes()) EXPECT_NEAR(kf.T_world_cam.z(), kCameraHeight, 1e-5);
	// The request is used up: the next estimate waits for reestimate_every keyframes again.
	EXPECT_FALSE(scale.update(map).has_value());
}

// The final bundle adjustment leaves a monocular map's overall scale free: finalEstimate()
// measures it once more over the whole map, whenever the last estimate was; a change beyond
// window_max_change is refused, and a map not metric yet is left alone.
TEST(MetricScale, TheFinalEstimateRescalesTheWholeAdjustedMap)
{
	for (const double grown : {1.04, 0.97, 1.15})
	{
		SCOPED_TRACE("map scaled by " + std::to_string(grown));
		sfm::SparseMap map;
		slam::MetricScale scale(options());
		const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2500)).id;
		addRoom(map, first, map.addKeyFrame(keyFrame(circlePose(6, kHeightMap), 2500)).id);
		for (int k = 1; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
		EXPECT_FALSE(scale.finalEstimate(map).has_value()) << "not metric yet";
		EXPECT_EQ(scale.stats().estimates, 0);
		ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		map.rescale(grown);
		const auto s = scale.finalEstimate(map);
		if (std::abs(grown - 1) > options().windowMaxChange)
		{
			EXPECT_FALSE(s.has_value());
			for (const auto& [id, kf] : map.keyframes()) EXPECT_NEAR(kf.T_world_cam.z(), grown * kCameraHeight, 1e-5);
			continue;
		}
		ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
		EXPECT_TRUE(s->wholeMap());
		EXPECT_NEAR(s->factor, 1.0 / grown, 1e-6);
		for (const auto& [id, kf] : map.keyframes()) EXPECT_NEAR(kf.T_world_cam.z(), kCameraHeight, 1e-5);
		ASSERT_TRUE(scale.floorPlane().has_value());
		EXPECT_NEAR(scale.floorPlane()->offset, 0.0, 1e-5);  // the floor plane is z = 0 again
		EXPECT_EQ(scale.stats().applied, 2);
	}
	// Switched off, nothing is estimated.
	auto off = options();
	off.finalEstimate = false;
	sfm::SparseMap map;
	slam::MetricScale scale(off);
	const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2500)).id;
	addRoom(map, first, map.addKeyFrame(keyFrame(circlePose(6, kHeightMap), 2500)).id);
	for (int k = 1; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
	ASSERT_TRUE(scale.update(map).has_value());
	map.rescale(1.04);
	EXPECT_FALSE(scale.finalEstimate(map).has_value());
	EXPECT_EQ(scale.stats().estimates, 1);
}

TEST(MetricScale, IsRetriedAtEveryKeyFrameUntilTheFloorIsFound)
{
	sfm::SparseMap map;
	slam::MetricScale scale(options());
	// No floor yet (walls only above the cameras' horizontal): refused, the map unchanged.
	const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2510)).id;
	for (int i = 0; i < 10; i++) map.addLandmark({2.0, 0.1 * i, 1.0}, first, i);
	for (int k = 1; k < 4; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
	EXPECT_FALSE(scale.update(map).has_value());
	EXPECT_EQ(scale.stats().estimates, 1);
	EXPECT_FALSE(scale.metric());
	EXPECT_NEAR(map.keyframe(first).T_world_cam.z(), kHeightMap, 1e-15);
	// The next keyframe brings the floor: tried again at once.
	const auto withRoom = map.addKeyFrame(keyFrame(circlePose(4, kHeightMap), 2510)).id;
	addRoom(map, withRoom, first, 10);
	const auto s = scale.update(map);
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	EXPECT_NEAR(s->factor, kCameraHeight / kHeightMap, 1e-6 * kCameraHeight / kHeightMap);
	EXPECT_EQ(scale.stats().estimates, 2);
}

// Points triangulated over a short baseline (here 1 mm of map units: rays 0.03 deg apart)
// may lie far off their surface: 200 of them scattered under the floor would make every
// plane "not the floor", and min_point_parallax_deg leaves them out.
TEST(MetricScale, PointsSeenOverAShortBaselineAreLeftOutOfTheFloorSearch)
{
	for (const double minParallax : {2.0, 0.0})
	{
		SCOPED_TRACE(minParallax);
		sfm::SparseMap map;
		const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2700)).id;
		addRoom(map, first, map.addKeyFrame(keyFrame(circlePose(6, kHeightMap), 2500)).id);
		CPose3D near = circlePose(0, kHeightMap);
		near.x_incr(0.001);
		const auto close = map.addKeyFrame(keyFrame(near, 2700)).id;
		std::mt19937 rng(9);
		std::uniform_real_distribution<double> u(-1.5, 1.5), under(-0.6, -0.2);
		for (int i = 0; i < 200; i++) map.addObservation(map.addLandmark({u(rng), u(rng), under(rng)}, first, 2500 + i), close, 2500 + i);
		for (int k = 1; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
		auto o = options();
		o.minPointParallaxDeg = minParallax;
		slam::MetricScale scale(o);
		const auto s = scale.update(map);
		if (minParallax > 0)
		{
			ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
			EXPECT_NEAR(s->factor, kCameraHeight / kHeightMap, 1e-6 * kCameraHeight / kHeightMap);
		}
		else
		{
			EXPECT_FALSE(s.has_value());
			EXPECT_NE(scale.stats().lastMessage.find("floor not seen"), std::string::npos) << scale.stats().lastMessage;
		}
	}
}

// A map whose points were all seen over a short baseline: the well-triangulated points are too
// few, and the estimate comes from every point.
TEST(MetricScale, FallsBackOnEveryPointWhenTheWellTriangulatedOnesGiveNoEstimate)
{
	sfm::SparseMap map;
	const auto first = map.addKeyFrame(keyFrame(circlePose(0, kHeightMap), 2500)).id;
	CPose3D near = circlePose(0, kHeightMap);
	near.x_incr(0.001);
	addRoom(map, first, map.addKeyFrame(keyFrame(near, 2500)).id);
	for (int k = 1; k < 12; k++) map.addKeyFrame(keyFrame(circlePose(k, kHeightMap), 10));
	slam::MetricScale scale(options());
	const auto s = scale.update(map);
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	EXPECT_NEAR(s->factor, kCameraHeight / kHeightMap, 1e-6 * kCameraHeight / kHeightMap);
}

TEST(MetricScale, NeedsACameraHeightAndValidOptions)
{
	EXPECT_THROW(slam::MetricScale(slam::MetricScaleOptions()), std::invalid_argument);
	auto o = options();
	o.reestimateEvery = 0;
	EXPECT_THROW(slam::MetricScale{o}, std::invalid_argument);
	EXPECT_FALSE(slam::MetricScaleOptions().enabled());
	EXPECT_TRUE(options().enabled());
}

// The floor points' plane is tilted by 0.3 deg (their fit, not the truth). Keyframes on a circle
// of 1 map unit (2.6 m once metric: 1.84 m of spread) at one height: the maps' floor is the
// plane under the path, camera_height below it. The same keyframes 3 cm (metric) above and
// below that height in turn (a hand-held camera): the maps' floor is the points' plane.
TEST(MetricScale, TheMapsFloorLiesUnderALevelCameraPathAndComesFromThePointsOtherwise)
{
	const double slope = std::tan(0.3 * M_PI / 180);
	for (const double wobble : {0.0, 0.03 * kHeightMap / kCameraHeight})
	{
		SCOPED_TRACE(wobble);
		sfm::SparseMap map;
		const auto pose = [&](int k) {
			const double a = 0.5 * k;
			return camera(std::cos(a), std::sin(a), kHeightMap + (k % 2 ? wobble : -wobble), a);
		};
		const auto first = map.addKeyFrame(keyFrame(pose(0), 2500)).id;
		addRoom(map, first, map.addKeyFrame(keyFrame(pose(1), 2500)).id, 0, slope);
		for (int k = 2; k < 14; k++) map.addKeyFrame(keyFrame(pose(k), 10));
		slam::MetricScale scale(options());
		ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		ASSERT_TRUE(scale.floorPlane().has_value());
		const auto& floor = *scale.floorPlane();
		ASSERT_EQ(scale.log().size(), 1u);
		if (wobble == 0)
		{
			EXPECT_NEAR(floor.normal.z(), 1.0, 1e-12);
			EXPECT_NEAR(floor.offset, kCameraHeight - map.keyframe(first).T_world_cam.z(), 1e-9);
			EXPECT_NE(scale.log()[0].find("floor under the camera path"), std::string::npos) << scale.log()[0];
		}
		else
		{
			EXPECT_NEAR(std::acos(floor.normal.z()) * 180 / M_PI, 0.3, 0.01);
			EXPECT_NE(scale.log()[0].find("floor from the map points (camera path: "), std::string::npos)
				<< scale.log()[0];
		}
	}
}

namespace
{
/** Keyframes along x at the camera height, 0.5 x `unit` map units apart and looking along x,
 * and the floor ahead of every other keyframe (400 points seen from it and the next one),
 * camera_height x `unit` under them: a stretch whose scale drifted by `unit` (1: metric). */
struct DriftingPath
{
	explicit DriftingPath(sfm::SparseMap& m) : map(m) {}
	void addStretch(int from, int to, double unit)
	{
		for (int k = from; k < to; k++, x += 0.5 * unit) ids.push_back(map.addKeyFrame(keyFrame(camera(x, 0, kCameraHeight, 0), keypoints)).id);
		for (int k = from; k + 1 < to; k += 2)
		{
			const double xk = map.keyframe(ids[static_cast<std::size_t>(k)]).T_world_cam.x();
			std::uniform_real_distribution<double> ux(xk + 1.0 * unit, xk + 4.0 * unit), uy(-2 * unit, 2 * unit);
			newestFloor.clear();
			for (int i = 0; i < 400; i++)
			{
				const auto l = map.addLandmark({ux(rng), uy(rng), kCameraHeight * (1 - unit)}, ids[static_cast<std::size_t>(k + 1)], i);
				map.addObservation(l, ids[static_cast<std::size_t>(k)], i);
				newestFloor.push_back(l);
			}
		}
	}
	/** `n` stray points 0.6-1.2 units under the floor ahead of keyframe pair (k, k + 1), seen
	 * from both (keypoints from 400 on). */
	void addStrayPoints(int k, int n)
	{
		const auto a = ids[static_cast<std::size_t>(k)], b = ids[static_cast<std::size_t>(k + 1)];
		const double xk = map.keyframe(a).T_world_cam.x();
		std::uniform_real_distribution<double> ux(xk + 1.0, xk + 4.0), uy(-2, 2), uz(-1.2, -0.6);
		for (int i = 400; i < 400 + n; i++) map.addObservation(map.addLandmark({ux(rng), uy(rng), uz(rng)}, b, i), a, i);
	}
	sfm::SparseMap& map;
	int keypoints{400};
	std::mt19937 rng{3};
	std::vector<sfm::KeyFrameId> ids;
	std::vector<sfm::LandmarkId> newestFloor;  //!< the floor points of the newest pair
	double x{0};
};
}  // namespace


// A long run whose scale drifted: along a straight, level path the keyframes and floor of the
// first 30 keyframes are metric (cameras camera_height above the floor, 0.5 m apart), those of
// the newest 20 came out 20 % small (steps of 0.4 map units, the floor 0.8 camera_height under
// the same level path). Over the whole map the floor is the metric one, under both stretches'
// points, and the estimate keeps the scale (factor 1). Along the newest window_path_length of
// path it is the scale where the camera is, camera_height / (0.8 camera_height) = 1.25: the
// window alone is rescaled (its oldest keyframe and the map before it stay, the newest keyframe's
// content grows by 1.25 about it), or the whole map with rescale_whole_map; a window_max_change
// below 0.25 refuses the estimate and leaves the map as it was.
TEST(MetricScale, AfterTheFirstEstimateTheNewestStretchOfThePathIsMeasuredAndRescaled)
{
	constexpr double kDrift = 0.8;
	constexpr int kMetric = 30, kDrifted = 20;
	struct Case
	{
		double window;
		bool wholeMapOption;
		double maxChange;
	};
	for (const auto& [window, wholeMapOption, maxChange] : {Case{4.2, false, 0.3}, Case{4.2, true, 0.3}, Case{4.2, false, 0.2}, Case{0.0, false, 0.3}})
	{
		SCOPED_TRACE(std::to_string(window) + " " + std::to_string(maxChange) + (wholeMapOption ? " whole map" : ""));
		const bool refused = maxChange < 1 / kDrift - 1;
		sfm::SparseMap map;
		auto o = options();
		o.windowPathLength = window;
		o.rescaleWholeMap = wholeMapOption;
		o.windowMaxChange = maxChange;
		o.reestimateEvery = 1;
		slam::MetricScale scale(o);
		DriftingPath path(map);
		const auto& ids = path.ids;
		path.addStretch(0, kMetric, 1.0);
		const auto first = scale.update(map);
		ASSERT_TRUE(first.has_value()) << scale.stats().lastMessage;
		EXPECT_NEAR(first->factor, 1.0, 1e-6);
		EXPECT_TRUE(first->wholeMap());
		path.addStretch(kMetric, kMetric + kDrifted, kDrift);
		std::map<sfm::KeyFrameId, CPose3D> before;
		for (const auto& [id, kf] : map.keyframes()) before[id] = kf.T_world_cam;
		const auto s = scale.update(map);
		ASSERT_EQ(scale.log().size(), 2u);
		if (refused)
		{
			EXPECT_FALSE(s.has_value());
			EXPECT_NE(scale.log()[1].find("exceeds window_max_change"), std::string::npos) << scale.log()[1];
			for (const auto& [id, T] : before) EXPECT_EQ(map.keyframe(id).T_world_cam.asVectorVal(), T.asVectorVal()) << id;
			continue;
		}
		ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
		if (window == 0)
		{
			EXPECT_NEAR(s->factor, 1.0, 1e-6);
			EXPECT_NE(scale.log()[1].find("keyframe 49, 50 keyframes"), std::string::npos) << scale.log()[1];
			continue;
		}
		EXPECT_NEAR(s->factor, 1.0 / kDrift, 1e-6);
		// 4.2 map units of path at 0.4 between keyframes: the newest 11.
		EXPECT_NE(scale.log()[1].find("keyframe 49, 11 keyframes"), std::string::npos) << scale.log()[1];
		if (wholeMapOption)
		{
			EXPECT_TRUE(s->wholeMap());
			EXPECT_NEAR(map.keyframe(ids.front()).T_world_cam.z(), kCameraHeight / kDrift, 1e-6);
			continue;
		}
		ASSERT_FALSE(s->wholeMap());
		ASSERT_EQ(s->newScales.size(), 11u);
		EXPECT_EQ(s->newScales.begin()->first, ids[kMetric + kDrifted - 11]);
		EXPECT_NEAR(s->newScales.begin()->second, 1.0, 1e-12);
		EXPECT_NEAR(s->newScales.rbegin()->second, 1.0 / kDrift, 1e-12);
		// The map before the window and the window's oldest keyframe stay; the path stays level.
		for (const auto& [id, T] : before)
		{
			const auto& now = map.keyframe(id).T_world_cam;
			if (id <= ids[kMetric + kDrifted - 11])
			{
				EXPECT_NEAR((now.asVectorVal() - T.asVectorVal()).norm(), 0.0, 1e-12) << id;
			}
			EXPECT_NEAR(now.z(), kCameraHeight, 1e-9) << id;
		}
		// From the window's middle on, steps and floor are metric: the newest keyframe's floor
		// points lie on the true floor.
		EXPECT_NEAR(map.keyframe(ids.back()).T_world_cam.x() - map.keyframe(ids[ids.size() - 2]).T_world_cam.x(), 0.5, 1e-9);
		for (const auto l : path.newestFloor) ASSERT_NEAR(map.landmark(l).p_world.z(), 0.0, 1e-9);
	}
}

namespace
{
/** Keyframes 0.5 map units apart along x at the camera height, looking along x, and the floor
 * ahead of each pair (400 points seen by both); a share of the points lies 0.2-1 units under it. */
struct StraightPath
{
	explicit StraightPath(sfm::SparseMap& m) : map(m) {}
	void addStretch(int from, int to, double strayShare)
	{
		for (int k = from; k < to; k++) ids.push_back(map.addKeyFrame(keyFrame(camera(0.5 * k, 0, kCameraHeight, 0), 400)).id);
		std::uniform_real_distribution<double> U(0, 1);
		for (int k = from; k + 1 < to; k += 2)
		{
			const double xk = 0.5 * k;
			for (int i = 0; i < 400; i++)
			{
				const double z = U(rng) < strayShare ? -0.2 - 0.8 * U(rng) : 0.0;
				map.addObservation(map.addLandmark({xk + 1.0 + 3.0 * U(rng), -2.0 + 4.0 * U(rng), z}, ids[k + 1], i), ids[k], i);
			}
		}
	}
	sfm::SparseMap& map;
	std::mt19937 rng{4};
	std::vector<sfm::KeyFrameId> ids;
};

/** Options whose window is the newest 4.2 map units of path, estimating at every keyframe. */
slam::MetricScaleOptions newestStretchWindow()
{
	auto o = options();
	o.windowPathLength = 4.2;
	o.reestimateEvery = 1;
	return o;
}

/** Options whose window is always the whole map (window_path_length far above any test path),
 * estimating at every keyframe, with window_max_below_share `maxBelowShare`. */
slam::MetricScaleOptions wholeMapWindow(double maxBelowShare)
{
	auto o = options();
	o.windowPathLength = 100;
	o.reestimateEvery = 1;
	o.windowMaxBelowShare = maxBelowShare;
	return o;
}
}  // namespace

// Along the newest stretch a monocular map keeps stray points under its floor. Here 4 % of the
// window's points lie 0.2-1 m under it: the stricter max_below_share refuses the floor ("points
// under every large plane"), window_max_below_share = 3 takes it, and the scale stays exact.
TEST(MetricScale, TheWindowSearchTakesAFloorWithStrayPointsUnderIt)
{
	for (const double share : {3.0, 0.5})
	{
		SCOPED_TRACE(share);
		sfm::SparseMap map;
		auto o = newestStretchWindow();
		o.windowMaxBelowShare = share;
		slam::MetricScale scale(o);
		StraightPath path(map);
		path.addStretch(0, 30, 0.0);
		ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		path.addStretch(30, 50, 0.04);
		const auto s = scale.update(map);
		if (share > 1)
		{
			ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
			EXPECT_FALSE(s->wholeMap());
			EXPECT_NEAR(s->factor, 1.0, 1e-6);
		}
		else
		{
			EXPECT_FALSE(s.has_value());
			EXPECT_NE(scale.stats().lastMessage.find("the lowest large plane has"), std::string::npos) << scale.stats().lastMessage;
		}
	}
}

// While the path is shorter than window_path_length, every estimate searches the whole map
// with the strict bound. Once the map is metric, a search that finds no clear floor that way
// is repeated with the generous bound: with the strict one alone a few per cent of stray points
// under the floor refused every estimate while the map's scale drifted. The map's first
// estimate keeps the strict bound.
TEST(MetricScale, OnceMetricTheWholeMapSearchTakesAFloorWithStrayPointsUnderIt)
{
	const auto run = [](double firstStrayShare, double share)
	{
		sfm::SparseMap map;
		slam::MetricScale scale(wholeMapWindow(share));
		StraightPath path(map);
		path.addStretch(0, 30, firstStrayShare);
		const auto first = scale.update(map);
		std::optional<slam::MetricScale::Rescale> second;
		if (first)
		{
			path.addStretch(30, 50, 0.04);
			second = scale.update(map);
		}
		return std::make_tuple(first, second, scale.stats().lastMessage);
	};
	// 160 stray points of 10000 under the floor: above the strict bound (max_below_share 0.5 of
	// the least support, 2 % of the points below the cameras: 1 %), within the generous one (6 %).
	{
		const auto [first, second, msg] = run(0.0, 3.0);
		ASSERT_TRUE(first.has_value());
		ASSERT_TRUE(second.has_value()) << msg;
		EXPECT_TRUE(second->wholeMap());
		EXPECT_NEAR(second->factor, 1.0, 1e-6);
		EXPECT_NE(msg.find("with window_max_below_share (floor not seen (points under every large plane): the lowest large plane has"), std::string::npos) << msg;
	}
	{
		const auto [first, second, msg] = run(0.0, 0.5);
		ASSERT_TRUE(first.has_value());
		EXPECT_FALSE(second.has_value());
		EXPECT_NE(msg.find("the lowest large plane has"), std::string::npos) << msg;
	}
	// The first estimate, on a map whose scale is not known yet, keeps the strict bound: 4 % of
	// stray points under the floor refuse it whatever window_max_below_share says.
	{
		const auto [first, second, msg] = run(0.04, 3.0);
		EXPECT_FALSE(first.has_value());
		EXPECT_NE(msg.find("the lowest large plane has"), std::string::npos) << msg;
	}
}

// After the final bundle adjustment a long map may come out slightly bent: here the second half
// of a straight, level 29.5 m path (its keyframes and the floor ahead of them) is turned 3 deg
// up about the middle, and then the whole map grew by 4 %. Every stretch of window_path_length
// (8 m) on one side of the bend has its cameras 1.04 x camera_height above its own floor, so the
// median over the stretches (5 of 7 lie on one side) is the map's scale, 1 / 1.04 exactly.
// One plane over the whole map (window_path_length 0: the map within one window) does not fit
// the bent floor: its estimate is another factor (here x0.957).
TEST(MetricScale, TheFinalEstimateOfALongMapIsTheMedianOfItsStretches)
{
	constexpr double kGrown = 1.04, kBendDeg = 3.0, kPivotX = 14.75;
	const auto run = [&](double windowPathLength)
	{
		sfm::SparseMap map;
		auto o = options();
		o.windowPathLength = windowPathLength;
		slam::MetricScale scale(o);
		StraightPath path(map);
		path.addStretch(0, 60, 0.0);
		EXPECT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		// The bend: a rotation about the y axis through (kPivotX, 0, 0), x towards +z.
		const CPose3D bend = CPose3D(kPivotX, 0, 0, 0, -kBendDeg * M_PI / 180, 0) + CPose3D(-kPivotX, 0, 0, 0, 0, 0);
		for (const auto id : path.ids)
			if (auto& kf = map.keyframe(id); kf.T_world_cam.x() > kPivotX) kf.T_world_cam = bend + kf.T_world_cam;
		for (const auto& [id, lm] : map.landmarks())
			if (lm.p_world.x() > kPivotX)
			{
				const auto q = bend.composePoint(mrpt::math::TPoint3D(lm.p_world.x(), lm.p_world.y(), lm.p_world.z()));
				map.landmark(id).p_world = Eigen::Vector3d(q.x, q.y, q.z);
			}
		map.rescale(kGrown);
		const auto s = scale.finalEstimate(map);
		return std::make_tuple(s, scale.log().back(), map.keyframe(path.ids.front()).T_world_cam.z());
	};
	{
		const auto [s, line, firstHeight] = run(8.0);
		ASSERT_TRUE(s.has_value()) << line;
		EXPECT_TRUE(s->wholeMap());
		EXPECT_NEAR(s->factor, 1.0 / kGrown, 1e-6) << line;
		EXPECT_NEAR(firstHeight, kCameraHeight, 1e-5);
		EXPECT_NE(line.find("7 stretches of 8 m, 7 with a floor"), std::string::npos) << line;
	}
	{
		const auto [s, line, firstHeight] = run(0.0);
		if (s)
		{
			EXPECT_GT(std::abs(s->factor - 1.0 / kGrown), 1e-3) << line;
		}
		EXPECT_EQ(line.find("stretches"), std::string::npos) << line;
	}
}

// That repeated search may only correct a drift: its generous bound could take a plane of
// stray points, so a change beyond window_max_change is left to the strict search. Here the
// metric map is put off in scale by `off` before the estimate over it.
TEST(MetricScale, TheRepeatedWholeMapSearchIsBoundByWindowMaxChange)
{
	const auto run = [](double off, double maxChange)
	{
		sfm::SparseMap map;
		auto o = wholeMapWindow(3.0);
		o.windowMaxChange = maxChange;
		slam::MetricScale scale(o);
		StraightPath path(map);
		path.addStretch(0, 30, 0.0);
		EXPECT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		path.addStretch(30, 50, 0.04);
		map.rescale(off);
		const auto second = scale.update(map);
		return std::make_pair(second, scale.stats().lastMessage);
	};
	{
		// A drift of 5 %: taken, back to metres.
		const auto [s, msg] = run(1.05, 0.1);
		ASSERT_TRUE(s.has_value()) << msg;
		EXPECT_TRUE(s->wholeMap());
		EXPECT_NEAR(s->factor, 1 / 1.05, 1e-6);
		EXPECT_NE(msg.find("with window_max_below_share (floor not seen"), std::string::npos) << msg;
	}
	{
		// 25 % off: refused, saying why.
		const auto [s, msg] = run(1.25, 0.1);
		EXPECT_FALSE(s.has_value());
		EXPECT_NE(msg.find("with window_max_below_share x0.8"), std::string::npos) << msg;
		EXPECT_NE(msg.find("exceeds window_max_change = 0.1"), std::string::npos) << msg;
		EXPECT_NE(msg.find("floor not seen (points under every large plane)"), std::string::npos) << msg;
	}
	{
		// Without the bound, the same search takes the factor.
		const auto [s, msg] = run(1.25, 0.0);
		ASSERT_TRUE(s.has_value()) << msg;
		EXPECT_NEAR(s->factor, 1 / 1.25, 1e-6);
	}
}

// A first estimate that was wrong leaves the whole map off in scale; once the map is longer than
// the window, the newest stretch then asks for a change beyond window_max_change. The estimate
// over the whole map says the same, so the whole map is rescaled (exactly back to metres), where
// a plane above the floor in the stretch alone is refused (previous test).
TEST(MetricScale, ALargeChangeThatTheWholeMapConfirmsRescalesTheWholeMap)
{
	sfm::SparseMap map;
	auto o = newestStretchWindow();
	slam::MetricScale scale(o);
	std::mt19937 rng(6);
	std::vector<sfm::KeyFrameId> ids;
	// Keyframes 0.5 m apart and floor points ahead of them, in a map of `unit` map units per metre.
	const auto addStretch = [&](int from, int to, double unit)
	{
		for (int k = from; k < to; k++) ids.push_back(map.addKeyFrame(keyFrame(camera(0.5 * unit * k, 0, unit * kCameraHeight, 0), 400)).id);
		std::uniform_real_distribution<double> U(0, 1);
		for (int k = from; k + 1 < to; k += 2)
			for (int i = 0; i < 400; i++)
				map.addObservation(
					map.addLandmark({unit * (0.5 * k + 1.0 + 3.0 * U(rng)), unit * (-2.0 + 4.0 * U(rng)), 0.0}, ids[k + 1], i), ids[k], i);
	};
	addStretch(0, 10, 1.0);
	ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
	// The map comes out 30 % too large (as after a first estimate on another plane), then grows.
	map.rescale(1.3);
	addStretch(10, 30, 1.3);
	const auto s = scale.update(map);
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	EXPECT_TRUE(s->wholeMap());
	EXPECT_NEAR(s->factor, 1 / 1.3, 1e-6);
	EXPECT_NE(scale.log().back().find("the whole map agrees"), std::string::npos) << scale.log().back();
	for (const auto& [id, kf] : map.keyframes()) EXPECT_NEAR(kf.T_world_cam.z(), kCameraHeight, 1e-6) << id;
}

// A map that grew 15 % at a turn: the estimates along the newest stretch say x0.87, beyond
// window_max_change, and the whole map (most of it metric) does not confirm them. A shrink is
// taken at the third estimate in a row that says it (window_persistent_shrink); a growth,
// which a plane above the floor also gives, never is.
TEST(MetricScale, AShrinkThatPersistsOverConsecutiveEstimatesIsTaken)
{
	struct Case
	{
		double unit;
		int persistent;
	};
	for (const auto& [unit, persistent] : {Case{1.15, 3}, Case{1.15, 0}, Case{1 / 1.15, 3}})
	{
		SCOPED_TRACE(std::to_string(unit) + ", window_persistent_shrink " + std::to_string(persistent));
		sfm::SparseMap map;
		auto o = newestStretchWindow();
		o.windowPersistentShrink = persistent;
		slam::MetricScale scale(o);
		DriftingPath path(map);
		path.keypoints = 500;
		path.addStretch(0, 40, 1.0);
		ASSERT_TRUE(scale.update(map).has_value()) << scale.stats().lastMessage;
		// Stray points under the metric floor, out of the newest stretch: the whole map's strict
		// search sees no clear floor (as in office_loop, where the whole map gave no estimate).
		for (int k = 0; k < 40; k += 2) path.addStrayPoints(k, 15);
		path.addStretch(40, 60, unit);
		for (int estimate = 1; estimate <= 4; estimate++)
		{
			if (estimate > 1) path.addStretch(56 + 2 * estimate, 58 + 2 * estimate, unit);
			const auto s = scale.update(map);
			const std::string& line = scale.log().back();
			if (estimate < 3 || persistent == 0 || unit < 1)
			{
				EXPECT_FALSE(s.has_value()) << line;
				EXPECT_NE(line.find("refused: a change of x"), std::string::npos) << line;
				EXPECT_EQ(line.find("the whole map agrees"), std::string::npos) << line;
				EXPECT_NE(line.find("the whole map gives no estimate"), std::string::npos) << line;
				if (unit > 1)
				{
					EXPECT_NE(line.find("(" + std::to_string(estimate) + " in a row)"), std::string::npos) << line;
				}
				continue;
			}
			ASSERT_TRUE(s.has_value()) << line;
			EXPECT_NEAR(s->factor, 1 / unit, 1e-6) << line;
			EXPECT_FALSE(s->wholeMap());
			EXPECT_NE(line.find("refused 2 times in a row before"), std::string::npos) << line;
			// From the window's middle on the path is metric again: its newest floor on z = 0.
			for (const auto l : path.newestFloor) ASSERT_NEAR(map.landmark(l).p_world.z(), 0.0, 1e-9);
			break;
		}
	}
}

// CameraHeightScaleEstimator (metric scale of a monocular map from the camera's height, issue
// 29) on synthetic maps: a 6 m x 6 m room (floor, a desk top with more points than the floor,
// walls, ceiling, gross outliers) mapped by cameras at a known height, every point with
// isotropic Gaussian noise, the whole map then scaled by an unknown factor k and moved by an
// arbitrary rigid transform. The recovered scale must be 1 / k within a bound derived from the
// noise; the refusals must name their reason.
#include <keygrid/core/VectorAngle.h>
#include <keygrid/sfm/CameraHeightScale.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/math/CMatrixFixed.h>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace
{
constexpr double kRoomHalf = 3.0, kRoomHeight = 2.5, kDeskHeight = 0.72;
/** The cameras' height [m]: a robot's head camera, with the desk top 0.38 m below it. */
constexpr double kCameraHeight = 1.1;
constexpr double kNoise = 0.01;  // point noise std [m], every axis
constexpr double kDeg = M_PI / 180.0;

/** Desk top: x in [1.4, 2.8], y in [-2.8, -2.0] (away from the cameras' path). */
bool onDesk(double x, double y) { return x >= 1.4 && x <= 2.8 && y >= -2.8 && y <= -2.0; }

struct RoomSpec
{
	int floorPoints{800}, deskPoints{1200}, wallPoints{1600}, ceilingPoints{400}, outliers{60};
	/** Points scattered under the desk top (chair, drawers), 0.1 .. 0.62 m high */
	int clutterPoints{0};
	int keyframes{24};
	/** Height of keyframe k [m] */
	std::function<double(int)> cameraHeight = [](int) { return kCameraHeight; };
	double pitchDeg{15};  //!< the cameras look down by this (plus up to 3 deg of jitter)
	unsigned seed{7};
};

/** A room in metres (z up, floor z = 0); labels tell which surface each point came from. */
struct Room
{
	std::vector<CPose3D> T_world_cam;
	std::vector<Eigen::Vector3d> points;
	std::vector<Eigen::Vector3d> floorTruth, deskTruth;  //!< noise-free floor and desk points
};

CPose3D poseFrom(const Eigen::Matrix3d& R, const Eigen::Vector3d& t)
{
	mrpt::math::CMatrixDouble33 Rm;
	mrpt::math::CVectorFixedDouble<3> tm;
	for (int i = 0; i < 3; i++)
	{
		tm[i] = t[i];
		for (int j = 0; j < 3; j++) Rm(i, j) = R(i, j);
	}
	return CPose3D::FromRotationAndTranslation(Rm, tm);
}

/** Optical frame (x right, y down, z forward) of a camera heading `yaw` about world z,
 * pitched down by `pitch` and rolled by `roll` about its axis [rad]. */
Eigen::Matrix3d cameraRotation(double yaw, double pitch, double roll)
{
	const Eigen::Vector3d fwd(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch));
	const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0);
	const Eigen::AngleAxisd rollAbout(roll, fwd);
	Eigen::Matrix3d R;
	R.col(0) = rollAbout * right;
	R.col(1) = rollAbout * fwd.cross(right);
	R.col(2) = fwd;
	return R;
}

Room makeRoom(const RoomSpec& s)
{
	std::mt19937 rng(s.seed);
	std::uniform_real_distribution<double> U(-1, 1), U01(0, 1);
	std::normal_distribution<double> N(0, kNoise);
	const auto noisy = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x() + N(rng), p.y() + N(rng), p.z() + N(rng)); };
	Room room;
	// Cameras on a 270 deg arc of radius 1.2 m, heading outwards: the mean of their -y axes is
	// off vertical by a few degrees, as a robot's that does not close a circle.
	for (int k = 0; k < s.keyframes; k++)
	{
		const double a = 1.5 * M_PI * k / (s.keyframes - 1);
		const Eigen::Vector3d c(1.2 * std::cos(a), 1.2 * std::sin(a), s.cameraHeight(k));
		const Eigen::Matrix3d R = cameraRotation(a, (s.pitchDeg + 3 * U(rng)) * kDeg, 3 * U(rng) * kDeg);
		room.T_world_cam.push_back(poseFrom(R, c));
	}
	while (static_cast<int>(room.floorTruth.size()) < s.floorPoints)
	{
		const Eigen::Vector3d p(kRoomHalf * U(rng), kRoomHalf * U(rng), 0);
		if (!onDesk(p.x(), p.y())) room.floorTruth.push_back(p);
	}
	for (int i = 0; i < s.deskPoints; i++) room.deskTruth.emplace_back(2.1 + 0.7 * U(rng), -2.4 + 0.4 * U(rng), kDeskHeight);
	for (const auto& p : room.floorTruth) room.points.push_back(noisy(p));
	for (const auto& p : room.deskTruth) room.points.push_back(noisy(p));
	for (int i = 0; i < s.wallPoints; i++)
	{
		const double along = kRoomHalf * U(rng), z = kRoomHeight * U01(rng);
		const Eigen::Vector3d walls[4] = {{kRoomHalf, along, z}, {-kRoomHalf, along, z}, {along, kRoomHalf, z}, {along, -kRoomHalf, z}};
		room.points.push_back(noisy(walls[i % 4]));
	}
	for (int i = 0; i < s.ceilingPoints; i++) room.points.push_back(noisy({kRoomHalf * U(rng), kRoomHalf * U(rng), kRoomHeight}));
	for (int i = 0; i < s.clutterPoints; i++)
		room.points.push_back({2.1 + 0.7 * U(rng), -2.4 + 0.4 * U(rng), 0.1 + (kDeskHeight - 0.2) * U01(rng)});
	for (int i = 0; i < s.outliers; i++) room.points.push_back({kRoomHalf * U(rng), kRoomHalf * U(rng), kRoomHeight * U01(rng)});
	return room;
}

/** The map of a metric world: p_map = k (Q p + t). */
struct Similarity
{
	double k{1};
	Eigen::Matrix3d Q{Eigen::Matrix3d::Identity()};
	Eigen::Vector3d t{Eigen::Vector3d::Zero()};

	Eigen::Vector3d operator()(const Eigen::Vector3d& p) const { return k * (Q * p + t); }
	CPose3D operator()(const CPose3D& T) const
	{
		const auto Rm = T.getRotationMatrix();
		Eigen::Matrix3d R;
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) R(i, j) = Rm(i, j);
		return poseFrom(Q * R, (*this)(Eigen::Vector3d(T.x(), T.y(), T.z())));
	}
};

Similarity arbitraryMap(double k)
{
	Similarity S;
	S.k = k;
	S.Q = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()) * Eigen::AngleAxisd(2.1, Eigen::Vector3d::UnitX()))
			  .toRotationMatrix();
	S.t = Eigen::Vector3d(4.2, -1.3, 7.9);
	return S;
}

struct Map
{
	std::vector<CPose3D> T_world_cam;
	std::vector<Eigen::Vector3d> points;
};

Map toMap(const Room& room, const Similarity& S)
{
	Map m;
	for (const auto& T : room.T_world_cam) m.T_world_cam.push_back(S(T));
	for (const auto& p : room.points) m.points.push_back(S(p));
	return m;
}

CameraHeightScaleOptions optionsFor(double cameraHeight)
{
	CameraHeightScaleOptions o;
	o.cameraHeight = cameraHeight;
	return o;
}

/** Std of the estimated camera height [m] for a least-squares floor through n points with
 * noise std sigma along the normal: its offset at the centroid has std sigma / sqrt(n), its
 * tilt std sigma / (sqrt(n) r) about each horizontal axis (r: rms spread of the points along
 * the other, the smaller principal spread taken), which moves the height under a camera at
 * horizontal distance rho from the centroid by rho times the tilt. The tilt is also fitted to
 * the desk top and the walls, which only lowers it: this is an upper bound. */
double heightStd(const std::vector<Eigen::Vector3d>& floor, const std::vector<CPose3D>& cams, double sigma)
{
	Eigen::Vector2d c = Eigen::Vector2d::Zero();
	for (const auto& p : floor) c += p.head<2>();
	c /= static_cast<double>(floor.size());
	Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
	for (const auto& p : floor) C += (p.head<2>() - c) * (p.head<2>() - c).transpose();
	C /= static_cast<double>(floor.size());
	const double r = std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C).eigenvalues()(0));
	double rho = 0;
	for (const auto& T : cams) rho = std::max(rho, std::hypot(T.x() - c.x(), T.y() - c.y()));
	const auto n = static_cast<double>(floor.size());
	return sigma / std::sqrt(n) * std::sqrt(1 + (rho / r) * (rho / r));
}
}  // namespace

TEST(CameraHeightScale, RecoversTheScaleOfAnArbitrarilyScaledAndMovedRoom)
{
	const RoomSpec spec;
	const Room room = makeRoom(spec);
	const Similarity S = arbitraryMap(0.37);
	const Map map = toMap(room, S);
	const CameraHeightScaleEstimator est(optionsFor(kCameraHeight));
	const auto r = est.estimate(map.T_world_cam, map.points);
	ASSERT_TRUE(r.ok) << r.message;
	// 4 std of the height estimate (derivation at heightStd), relative to the height.
	const double tol = 4 * heightStd(room.floorTruth, room.T_world_cam, kNoise) / kCameraHeight;
	const double err = r.scale * S.k - 1;
	std::cout << "scale " << r.scale << " (true " << 1 / S.k << "): relative error " << err << ", bound " << tol << ", " << r.passes
			  << " passes, " << r.message << "\n";
	EXPECT_LT(std::abs(err), tol);
	// Every camera is at kCameraHeight: only the plane's tilt spreads their heights, each by at
	// most twice the bound from the median one, and 1.4826 MAD stays below 1.4826 times that.
	EXPECT_LT(r.heightSpread, 2 * 1.4826 * tol);

	// The floor, not the desk: its normal is the world's up, the noise-free floor points lie on
	// it and the desk top stands kDeskHeight above it (to 3 cm, where taking the desk for the
	// floor would be 0.72 m off).
	const Eigen::Vector3d upMap = S.Q * Eigen::Vector3d::UnitZ();
	EXPECT_LT(std::acos(std::min(1.0, r.floorNormal.dot(upMap))) / kDeg, 0.5);
	double floorH = 0, deskH = 0;
	for (const auto& p : room.floorTruth) floorH += (r.floorNormal.dot(S(p)) + r.floorOffset) * r.scale;
	for (const auto& p : room.deskTruth) deskH += (r.floorNormal.dot(S(p)) + r.floorOffset) * r.scale;
	floorH /= static_cast<double>(room.floorTruth.size());
	deskH /= static_cast<double>(room.deskTruth.size());
	EXPECT_NEAR(floorH, 0.0, 3 * kNoise);
	EXPECT_NEAR(deskH, kDeskHeight, 3 * kNoise);
	// Its inliers are the floor's points (the band is 5 noise stds wide), plus the wall points
	// within 5 cm of the floor (1600 * 0.05 / 2.5 = 32) and the outliers in the band
	// (60 * 0.1 / 2.5 = 2.4): 834 expected, bounded here by 4 Poisson stds of the extras; the
	// desk top has 1200.
	const double extras = spec.wallPoints * 0.05 / kRoomHeight + spec.outliers * 0.1 / kRoomHeight;
	EXPECT_GE(r.floorInliers, spec.floorPoints);
	EXPECT_LT(r.floorInliers, spec.floorPoints + extras + 4 * std::sqrt(extras));
	EXPECT_EQ(r.keyframeHeights.size(), room.T_world_cam.size());
}

TEST(CameraHeightScale, IsScaleEquivariantAndRescalingGivesAMetricMap)
{
	const Room room = makeRoom({});
	const CameraHeightScaleEstimator est(optionsFor(kCameraHeight));
	Map a = toMap(room, arbitraryMap(0.37));
	const Map b = toMap(room, arbitraryMap(41.0));
	const auto ra = est.estimate(a.T_world_cam, a.points);
	const auto rb = est.estimate(b.T_world_cam, b.points);
	ASSERT_TRUE(ra.ok && rb.ok) << ra.message << " / " << rb.message;
	// Every tolerance of the search is applied in the map rescaled to metres, so the estimate
	// does not depend on the map's units (up to rounding).
	EXPECT_NEAR(ra.scale * 0.37 / (rb.scale * 41.0), 1.0, 1e-9);
	EXPECT_EQ(ra.floorInliers, rb.floorInliers);

	// The map rescaled by s has the cameras at camera_height: its own scale is 1.
	rescaleMap(ra.scale, a.T_world_cam, a.points);
	const auto rm = est.estimate(a.T_world_cam, a.points);
	ASSERT_TRUE(rm.ok) << rm.message;
	EXPECT_NEAR(rm.scale, 1.0, 1e-9);
	EXPECT_NEAR(rm.heightMap, kCameraHeight, 1e-9);
}

TEST(CameraHeightScale, RescaleMapScalesCentresAndPointsAboutTheOrigin)
{
	std::vector<CPose3D> poses{CPose3D(1, -2, 3, 0.3, -0.2, 0.1), CPose3D(-0.5, 0.25, 4, 2.0, 0.4, -1.0)};
	const auto before = poses;
	std::vector<Eigen::Vector3d> points{{1, 2, 3}, {-4, 0.5, 0}};
	rescaleMap(2.5, poses, points);
	for (std::size_t k = 0; k < poses.size(); k++)
	{
		EXPECT_DOUBLE_EQ(poses[k].x(), 2.5 * before[k].x());
		EXPECT_DOUBLE_EQ(poses[k].y(), 2.5 * before[k].y());
		EXPECT_DOUBLE_EQ(poses[k].z(), 2.5 * before[k].z());
		EXPECT_EQ(poses[k].getRotationMatrix(), before[k].getRotationMatrix());
	}
	EXPECT_EQ(points[0], Eigen::Vector3d(2.5, 5, 7.5));
	EXPECT_EQ(points[1], Eigen::Vector3d(-10, 1.25, 0));
}

TEST(CameraHeightScale, RefusesTooFewKeyframes)
{
	const Room room = makeRoom({});
	const std::vector<CPose3D> two(room.T_world_cam.begin(), room.T_world_cam.begin() + 2);
	const auto r = CameraHeightScaleEstimator(optionsFor(kCameraHeight)).estimate(two, room.points);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, CameraHeightScaleFailure::TooFewKeyframes) << r.message;
	EXPECT_NE(r.message.find("min_keyframes"), std::string::npos) << r.message;
}

TEST(CameraHeightScale, RefusesAMapWithNothingBelowTheCameras)
{
	// Ceiling and the walls' upper parts only: no point is seen under the horizontal.
	RoomSpec spec;
	spec.floorPoints = spec.deskPoints = spec.outliers = 0;
	Room room = makeRoom(spec);
	room.points.erase(
		std::remove_if(room.points.begin(), room.points.end(), [](const Eigen::Vector3d& p) { return p.z() < kCameraHeight + 0.4; }), room.points.end());
	const auto r = CameraHeightScaleEstimator(optionsFor(kCameraHeight)).estimate(room.T_world_cam, room.points);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, CameraHeightScaleFailure::TooFewPointsBelow) << r.message;
	EXPECT_EQ(r.pointsBelow, 0u);
}

TEST(CameraHeightScale, RefusesWhenNoHorizontalPlaneHoldsEnoughPoints)
{
	// An untextured floor and no furniture: the map holds the walls only, seen from 1.4 m. A
	// horizontal band of +-5 cm through the 2.5 m high walls holds 10 / 250 of their 800 points,
	// some 32, fewer than min_floor_points = 50, while some 380 points lie below the cameras.
	RoomSpec spec;
	spec.floorPoints = spec.deskPoints = spec.outliers = spec.ceilingPoints = 0;
	spec.wallPoints = 800;
	spec.cameraHeight = [](int) { return 1.4; };
	const Room room = makeRoom(spec);
	const auto r = CameraHeightScaleEstimator(optionsFor(1.4)).estimate(room.T_world_cam, room.points);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, CameraHeightScaleFailure::NoFloorPlane) << r.message;
	EXPECT_GE(r.pointsBelow, 300u);
}

/** A refusal for want of a usable floor: no large plane at all, or none with (almost) nothing
 * under it. Which of the two depends on which planes RANSAC draws among the lowest points. */
bool noUsableFloor(CameraHeightScaleFailure f)
{
	return f == CameraHeightScaleFailure::NoFloorPlane || f == CameraHeightScaleFailure::FloorNotClear;
}

TEST(CameraHeightScale, DoesNotTakeATableTopWithPointsUnderItForTheFloor)
{
	// An untextured floor (no map points) and cameras at 1.4 m: the desk top holds the most
	// points, but the walls' lower parts (400 * 0.67 / 2.5, some 110) and clutter (50 points)
	// lie under it, and no horizontal band through those holds min_floor_points = 50 (+-5 cm of
	// the walls hold some 16 points, of the clutter some 10).
	RoomSpec spec;
	spec.floorPoints = 0;
	spec.wallPoints = 400;
	spec.clutterPoints = 50;
	spec.cameraHeight = [](int) { return 1.4; };
	const Room room = makeRoom(spec);
	const auto r = CameraHeightScaleEstimator(optionsFor(1.4)).estimate(room.T_world_cam, room.points);
	EXPECT_FALSE(r.ok);
	EXPECT_TRUE(noUsableFloor(r.failure)) << r.message;
	EXPECT_EQ(r.scale, 0.0);
}

TEST(CameraHeightScale, RefusesAFloorWithManyPointsUnderIt)
{
	// A glossy floor: 150 mirror images of the room lie 0.2 .. 1 m under it, more than half the
	// least support (50) that a floor may have under it.
	Room room = makeRoom({});
	std::mt19937 rng(11);
	std::uniform_real_distribution<double> U(-1, 1), U01(0, 1);
	for (int i = 0; i < 150; i++) room.points.push_back({kRoomHalf * U(rng), kRoomHalf * U(rng), -0.2 - 0.8 * U01(rng)});
	const Map map = toMap(room, arbitraryMap(0.37));
	const auto r = CameraHeightScaleEstimator(optionsFor(kCameraHeight)).estimate(map.T_world_cam, map.points);
	EXPECT_FALSE(r.ok);
	EXPECT_TRUE(noUsableFloor(r.failure)) << r.message;
	EXPECT_EQ(r.scale, 0.0);
}

TEST(CameraHeightScale, RefusesCamerasAtDifferentHeights)
{
	// Keyframes alternate between 0.8 m and 1.4 m: the floor is found, the heights disagree.
	RoomSpec spec;
	spec.cameraHeight = [](int k) { return k % 2 ? 1.4 : 0.8; };
	const Room room = makeRoom(spec);
	const Map map = toMap(room, arbitraryMap(0.37));
	const auto r = CameraHeightScaleEstimator(optionsFor(kCameraHeight)).estimate(map.T_world_cam, map.points);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, CameraHeightScaleFailure::HeightSpread) << r.message;
	// The heights themselves are right (to 4 std of the plane's height, see heightStd), and
	// every keyframe is 0.3 m off their 1.1 m median: spread 1.4826 * 0.3 / 1.1 = 0.40.
	ASSERT_EQ(r.keyframeHeights.size(), room.T_world_cam.size());
	const double tol = 4 * heightStd(room.floorTruth, room.T_world_cam, kNoise);
	for (std::size_t k = 0; k < room.T_world_cam.size(); k++)
		EXPECT_NEAR(r.keyframeHeights[k] / 0.37, room.T_world_cam[k].z(), tol) << "keyframe " << k;
	EXPECT_NEAR(r.heightSpread, 1.4826 * 0.3 / 1.1, 1.4826 * 3 * tol / 1.1);
}

namespace
{
/** Keyframes on a straight path along x (y = 0, kCameraHeight up) that turn from facing
 * yaw0 to yaw1 (about world z), pitched down 15 deg, with a constant mount roll; no noise. */
std::vector<CPose3D> straightPathTurning(int keyframes, double yaw0Deg, double yaw1Deg, double rollDeg)
{
	std::vector<CPose3D> cams;
	for (int k = 0; k < keyframes; k++)
	{
		const double t = static_cast<double>(k) / (keyframes - 1);
		const double yaw = (yaw0Deg + t * (yaw1Deg - yaw0Deg)) * kDeg;
		cams.push_back(poseFrom(cameraRotation(yaw, 15 * kDeg, rollDeg * kDeg), {-1.5 + 3.0 * t, 0, kCameraHeight}));
	}
	return cams;
}

/** A plane rolled by `tiltDeg` about the path's direction (x), through the line y = 0.5 at the
 * floor, rising towards +y: z = (y - 0.5) tan(tilt), for y in [0.5, 3]; Gaussian noise. Every
 * camera of straightPathTurning is at the same distance above it, (0.5 sin + h cos)(tilt). */
std::vector<Eigen::Vector3d> rolledPlane(int n, double tiltDeg, unsigned seed)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> U(0, 1);
	std::normal_distribution<double> N(0, kNoise);
	std::vector<Eigen::Vector3d> pts;
	for (int i = 0; i < n; i++)
	{
		const double x = -3 + 6 * U(rng), y = 0.5 + 2.5 * U(rng);
		pts.emplace_back(x + N(rng), y + N(rng), (y - 0.5) * std::tan(tiltDeg * kDeg) + N(rng));
	}
	return pts;
}
}  // namespace

TEST(CameraHeightScale, APlaneRolledAboutTheCamerasPathIsNotTheFloorOnceTheyTurned)
{
	// The cameras' positions cannot tell: on a straight path every one is 1.205 m above a plane
	// rolled 20 deg about the path, so a search that knows only their positions and mean -y
	// (level_min_turn_deg = 0) takes it for the floor, at a scale of 1.1 / 1.205.
	const double tilt = 20, hRolled = 0.5 * std::sin(tilt * kDeg) + kCameraHeight * std::cos(tilt * kDeg);
	const auto points = rolledPlane(1500, tilt, 5);
	const auto turning = straightPathTurning(24, 45, 135, 0);
	CameraHeightScaleOptions positionsOnly = optionsFor(kCameraHeight);
	positionsOnly.levelMinTurnDeg = 0;
	const auto fooled = CameraHeightScaleEstimator(positionsOnly).estimate(turning, points);
	ASSERT_TRUE(fooled.ok) << fooled.message;
	EXPECT_FALSE(fooled.searchedAroundTurnAxis);
	EXPECT_NEAR(fooled.scale, kCameraHeight / hRolled, 0.01);
	// Their x axes span the floor's directions: the turn axis is the world's z, 20 deg off that
	// plane's normal, and the turn 90 deg. That plane is refused, and the search around the
	// axis finds no floor.
	const CameraHeightScaleEstimator est(optionsFor(kCameraHeight));
	const auto r = est.estimate(turning, points);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, CameraHeightScaleFailure::NoFloorPlane) << r.message;
	EXPECT_TRUE(r.searchedAroundTurnAxis);
	EXPECT_NEAR(r.turnDeg, 90.0, 1e-6);
	EXPECT_LT((r.turnAxis - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
	// With the floor seen (500 points, a third of the rolled plane's, in y < 0.5 where the
	// rolled plane runs under it), the search around the turn axis takes it: the true scale 1.
	auto withFloor = points;
	std::mt19937 rng(9);
	std::uniform_real_distribution<double> U(0, 1);
	std::normal_distribution<double> N(0, kNoise);
	for (int i = 0; i < 500; i++) withFloor.emplace_back(-3 + 6 * U(rng) + N(rng), -2.5 + 3.0 * U(rng) + N(rng), N(rng));
	// The rolled plane's foot (its first 0.14 m, in the floor's 5 cm band) lifts and tilts the
	// fitted floor a little: within the 2 % of issue 29's scale target.
	const auto rf = est.estimate(turning, withFloor);
	ASSERT_TRUE(rf.ok) << rf.message;
	EXPECT_NEAR(rf.scale, 1.0, 0.02);
	EXPECT_LT(rf.floorToTurnAxisDeg, 1.0);
	// A constant mount roll of 2 deg tilts the turn axis by about as much (the x axes' common
	// tilt is sin(roll) cos(pitch); a 90 deg arc adds a little): still within
	// level_max_tilt_deg (4) of the floor, which is fitted to the points alone.
	const auto rolled = est.estimate(straightPathTurning(24, 45, 135, 2), withFloor);
	ASSERT_TRUE(rolled.ok) << rolled.message;
	EXPECT_NEAR(rolled.scale, 1.0, 0.02);
	EXPECT_GT(rolled.floorToTurnAxisDeg, 0.5);
	EXPECT_LT(rolled.floorToTurnAxisDeg, 2.0 + 0.5);
	// Cameras that turn less than level_min_turn_deg (15) keep the search of the positions and
	// mean -y, and are fooled as before: the known limit of a path that has not turned yet.
	const auto straight = est.estimate(straightPathTurning(24, 85, 95, 0), points);
	EXPECT_FALSE(straight.searchedAroundTurnAxis);
	EXPECT_NEAR(straight.turnDeg, 10.0, 1e-6);
	ASSERT_TRUE(straight.ok) << straight.message;
	EXPECT_NEAR(straight.scale, kCameraHeight / hRolled, 0.01);
}

namespace
{
/** A floor strip (z = 0) under the path of straightPathTurning and, beside it, a larger table
 * top 0.7 m high tilted by `topTiltDeg` about x (rising towards +y); Gaussian noise. */
std::vector<Eigen::Vector3d> floorAndTiltedTop(double topTiltDeg, unsigned seed)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> U(0, 1);
	std::normal_distribution<double> N(0, kNoise);
	std::vector<Eigen::Vector3d> pts;
	for (int i = 0; i < 600; i++) pts.emplace_back(-3 + 6 * U(rng) + N(rng), -2.5 + 2.5 * U(rng) + N(rng), N(rng));
	for (int i = 0; i < 2400; i++)
	{
		const double x = -3 + 6 * U(rng), y = 0.5 + 2.5 * U(rng);
		pts.emplace_back(x + N(rng), y + N(rng), 0.7 + (y - 1.75) * std::tan(topTiltDeg * kDeg) + N(rng));
	}
	return pts;
}
}  // namespace

TEST(CameraHeightScale, AFloorTiltedOffTheTurnAxisByItsRefinementIsRefused)
{
	// A mount roll of 3 deg tilts the keyframes' turn axis by atan(0.0560 / 0.9984) = 3.21 deg
	// (the x axes' common tilt, sin(roll) cos(pitch), over a 90 deg arc).
	const auto cams = straightPathTurning(24, 45, 135, 3);
	const CameraHeightScaleEstimator est(optionsFor(kCameraHeight));
	// With a level table top, the level floor is 3.2 deg off that axis, within
	// level_max_tilt_deg (4): taken at the true scale.
	const auto level = est.estimate(cams, floorAndTiltedTop(0, 3));
	ASSERT_TRUE(level.ok) << level.message;
	EXPECT_NEAR(level.scale, 1.0, 0.02);
	const double axisTiltDeg = keygrid::core::angleBetween(level.turnAxis, Eigen::Vector3d::UnitZ()) / kDeg;
	EXPECT_NEAR(axisTiltDeg, 3.21, 0.05);
	EXPECT_NEAR(level.floorToTurnAxisDeg, axisTiltDeg, 0.5);
	// A table top tilted 3 deg about x (perpendicular to the axis' tilt) is within the floor
	// refinement's refine_tilt_deg (5) of the floor, and four times the floor's points: the
	// common normal leans towards it, between the floor's and the top's, so it ends more than
	// 4 deg and at most hypot(3.21, 3) deg off the axis. Refused both times, the second after
	// the search around the turn axis, whose points alone gave a floor within 4 deg: the scale
	// it would have given is more than 2 % off.
	const auto tilted = est.estimate(cams, floorAndTiltedTop(-3, 3));
	EXPECT_FALSE(tilted.ok);
	EXPECT_EQ(tilted.failure, CameraHeightScaleFailure::OffTurnAxis) << tilted.message;
	EXPECT_TRUE(tilted.searchedAroundTurnAxis);
	EXPECT_GT(tilted.floorToTurnAxisDeg, 4.0);
	EXPECT_LE(tilted.floorToTurnAxisDeg, std::hypot(axisTiltDeg, 3.0) + 0.1);
	EXPECT_GT(std::abs(tilted.scale - 1.0), 0.02);
	EXPECT_NE(tilted.message.find("after its refinement"), std::string::npos) << tilted.message;
}

TEST(CameraHeightScale, TheTurnIsTheArcTheCamerasHeadingsCoverWhicheverWayTheyFace)
{
	// Whatever the heading, cameras that all face one way have not turned, and cameras that
	// turn from yaw to yaw + 10 deg have turned 10 deg (the estimate is refused or not, the turn
	// is measured before the floor search). The room is the fixture's, under the same path.
	const auto points = rolledPlane(1500, 0, 5);
	const CameraHeightScaleEstimator est(optionsFor(kCameraHeight));
	for (int yaw = 0; yaw < 360; yaw += 15)
	{
		EXPECT_NEAR(est.estimate(straightPathTurning(24, yaw, yaw, 0), points).turnDeg, 0.0, 1e-6) << "yaw " << yaw;
		EXPECT_NEAR(est.estimate(straightPathTurning(24, yaw, yaw + 10, 0), points).turnDeg, 10.0, 1e-6) << "yaw " << yaw;
		EXPECT_NEAR(est.estimate(straightPathTurning(24, yaw, yaw + 300, 0), points).turnDeg, 300.0, 1e-6) << "yaw " << yaw;
	}
}

TEST(CameraHeightScaleOptions, IniRoundTripAndValidation)
{
	CameraHeightScaleOptions o;
	o.cameraHeight = 0.42;
	o.maxHeightSpread = 0.03;
	o.minKeyframes = 7;
	o.levelMaxTiltDeg = 4.5;
	mrpt::config::CConfigFileMemory saved;
	o.saveToConfigFile(saved, "mono");
	const mrpt::config::CConfigFileMemory cfg(saved.getContent());
	CameraHeightScaleOptions back;
	back.loadFromConfigFile(cfg, "mono");
	EXPECT_EQ(back.cameraHeight, 0.42);
	EXPECT_EQ(back.maxHeightSpread, 0.03);
	EXPECT_EQ(back.minKeyframes, 7);
	EXPECT_EQ(back.levelMaxTiltDeg, 4.5);

	CameraHeightScaleOptions bad;
	bad.minDepressionDeg = 90;
	try
	{
		bad.validate("mono");
		ADD_FAILURE() << "min_depression_deg = 90 accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[mono] min_depression_deg"), std::string::npos) << e.what();
	}
	// The default leaves the height unknown: valid options, but no estimator.
	EXPECT_NO_THROW(CameraHeightScaleOptions{}.validate());
	EXPECT_THROW(CameraHeightScaleEstimator{CameraHeightScaleOptions{}}, std::invalid_argument);
}

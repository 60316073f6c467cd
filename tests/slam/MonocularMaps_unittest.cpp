// slam::MetricMaps in monocular mode with a camera height: a synthetic square room in map units
// (walls 2 map units from the centre, keyframe cameras 0.5 map units above the floor) seen by
// keyframes without depth. The 2D grid stores their map points until slam::MetricScale gives
// the map metric scale (camera_height / h_map = 2.6 m per unit); then it is rebuilt in metres
// on the floor plane of that estimate. Checked against the room's ground truth: the walls at
// 5.2 m from the centre in the floor frame, and the same grid as one fed the metric map directly.
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/MetricScale.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace monocular_maps_unittest
{
namespace
{
constexpr double kHeightMap = 0.5;  // camera height in map units
constexpr double kCameraHeight = 1.3;  // [m]
constexpr double kWall = 2.0;  // walls at |x| = 2 or |y| = 2 map units
constexpr int kKeyFrames = 12;

/** Optical frame of a camera on a circle of radius 0.4 map units, looking out, pitched 15 deg down. */
CPose3D circlePose(int k)
{
	const double yaw = 0.5 * k, pitch = 15 * M_PI / 180;
	const Eigen::Vector3d fwd(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch));
	const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0);
	const Eigen::Vector3d down = fwd.cross(right);
	mrpt::math::CMatrixDouble33 R;
	for (int i = 0; i < 3; i++)
	{
		R(i, 0) = right(i);
		R(i, 1) = down(i);
		R(i, 2) = fwd(i);
	}
	mrpt::math::CVectorFixedDouble<3> t;
	t[0] = 0.4 * std::cos(yaw);
	t[1] = 0.4 * std::sin(yaw);
	t[2] = kHeightMap;
	return CPose3D::FromRotationAndTranslation(R, t);
}

/** A keyframe without depth (monocular) observing its own floor and wall points of the room. */
sfm::KeyFrameId addKeyFrame(sfm::SparseMap& map, int k)
{
	constexpr int kFloor = 600, kWallPoints = 400;
	sfm::KeyFrame kf;
	kf.T_world_cam = circlePose(k);
	const auto n = static_cast<std::size_t>(kFloor + kWallPoints);
	kf.features.keypoints.resize(n);
	kf.features.undistorted.resize(n);
	kf.features.depth.assign(n, 0.f);
	kf.features.descriptors = cv::Mat(static_cast<int>(n), 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0};
	const auto id = map.addKeyFrame(std::move(kf)).id;
	std::mt19937 rng(static_cast<unsigned>(11 + k));
	// Walls start above the floor's inlier band (their feet would lift the fitted floor).
	std::uniform_real_distribution<double> u(-kWall, kWall), h(0.1, 1.2);
	int kp = 0;
	for (int i = 0; i < kFloor; i++) map.addLandmark({u(rng), u(rng), 0.0}, id, kp++);
	for (int i = 0; i < kWallPoints; i++)
	{
		const double along = u(rng), z = h(rng);
		const int wall = i % 4;
		const Eigen::Vector3d p = wall == 0 ? Eigen::Vector3d(kWall, along, z)
								  : wall == 1 ? Eigen::Vector3d(-kWall, along, z)
								  : wall == 2 ? Eigen::Vector3d(along, kWall, z)
											  : Eigen::Vector3d(along, -kWall, z);
		map.addLandmark(p, id, kp++);
	}
	return id;
}

std::unique_ptr<slam::MetricMaps> gridMaps()
{
	mrpt::config::CConfigFileMemory ini(
		"[MappingApplication]\n"
		"ismOccupancyGrid2D_count = 1\n"
		"[MappingApplication_ismOccupancyGrid2D_00_creationOpts]\n"
		"resolution = 0.05\n"
		"[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\n"
		"maxRange = 10\n");
	auto maps = std::make_unique<slam::MetricMaps>(ini, slam::MapFeedOptions{});
	maps->useFloorFromCameraHeight();
	return maps;
}

const CISMOccupancyGrid2D& grid(const slam::MetricMaps& maps)
{
	return dynamic_cast<const CISMOccupancyGrid2D&>(*maps.maps().maps.at(0));
}

slam::MetricScaleOptions scaleOptions()
{
	slam::MetricScaleOptions o;
	o.estimator.cameraHeight = kCameraHeight;
	return o;
}
}  // namespace

TEST(MonocularMaps, GridIsRebuiltInMetresOnTheCameraHeightFloor)
{
	sfm::SparseMap map;
	auto maps = gridMaps();
	for (int k = 0; k < kKeyFrames; k++) maps->insertKeyFrame(map, addKeyFrame(map, k), 0.1 * k);
	// No metric scale yet: no floor frame, the keyframes are only stored.
	EXPECT_FALSE(maps->T_world_floor().has_value());
	EXPECT_EQ(grid(*maps).countStates()[2], 0u);
	EXPECT_EQ(grid(*maps).keyframes().size(), static_cast<std::size_t>(kKeyFrames));

	slam::MetricScale scale(scaleOptions());
	const auto s = scale.update(map);
	ASSERT_TRUE(s.has_value()) << scale.stats().lastMessage;
	ASSERT_NEAR(s->factor, kCameraHeight / kHeightMap, 1e-5);
	const auto& plane = *scale.floorPlane();
	maps->applyRescale(map, s->factor, plane.normal, plane.offset);

	// The floor frame: z up on the true floor (world z = 0), in metres.
	ASSERT_TRUE(maps->T_world_floor().has_value());
	const CPose3D& T_world_floor = *maps->T_world_floor();
	EXPECT_NEAR(T_world_floor.z(), 0.0, 1e-6);
	EXPECT_NEAR(T_world_floor.rotateVector(mrpt::math::TVector3D(0, 0, 1)).z, 1.0, 1e-9);

	// Every occupied cell lies on a wall (at 2 map units = 5.2 m from the centre, within a
	// cell and a half), and the walls are found along their whole length.
	const auto& g = grid(*maps);
	const double wallM = kWall * s->factor, tol = 1.5 * g.resolution();
	std::size_t occupied = 0, offWall = 0;
	for (int cx = 0; cx < g.sizeX(); cx++)
		for (int cy = 0; cy < g.sizeY(); cy++)
		{
			if (g.cellState(cx, cy) != CellState::Occupied) continue;
			const auto w = T_world_floor.composePoint(mrpt::math::TPoint3D(g.idx2x(cx), g.idx2y(cy), 0));
			occupied++;
			if (std::abs(std::max(std::abs(w.x), std::abs(w.y)) - wallM) > tol) offWall++;
		}
	EXPECT_GT(occupied, 600u);
	EXPECT_EQ(offWall, 0u) << "of " << occupied << " occupied cells";
	std::size_t wallCells = 0, found = 0;
	for (double a = -wallM + 0.1; a < wallM - 0.1; a += g.resolution())
		for (const auto& w : {mrpt::math::TPoint3D(wallM, a, 0), mrpt::math::TPoint3D(-wallM, a, 0),
							  mrpt::math::TPoint3D(a, wallM, 0), mrpt::math::TPoint3D(a, -wallM, 0)})
		{
			const auto f = T_world_floor.inverseComposePoint(w);
			wallCells++;
			bool hit = false;
			for (int dx = -1; dx <= 1 && !hit; dx++)
				for (int dy = -1; dy <= 1 && !hit; dy++)
					hit = g.cellState(g.x2idx(f.x) + dx, g.y2idx(f.y) + dy) == CellState::Occupied;
			found += hit ? 1 : 0;
		}
	EXPECT_GE(static_cast<double>(found) / wallCells, 0.9) << found << " of " << wallCells << " wall cells";

	// The same grid as one fed the metric map directly: the rebuild forgot the old scale. The
	// stored points are floats, scaled after they were stored in one grid and before in the
	// other, so a ray may end in the neighbouring cell: a few cells may differ.
	auto direct = gridMaps();
	for (const auto& [id, kf] : map.keyframes()) direct->insertKeyFrame(map, id, 0.0);
	direct->applyRescale(map, 1.0, plane.normal, plane.offset);
	const auto& d = grid(*direct);
	std::size_t differ = 0;
	for (int cx = 0; cx < g.sizeX(); cx++)
		for (int cy = 0; cy < g.sizeY(); cy++)
			if (g.cellState(cx, cy) != d.stateAt(g.idx2x(cx), g.idx2y(cy))) differ++;
	EXPECT_LE(differ, occupied / 100) << "cells whose state differs from the directly fed grid's";
}

TEST(MonocularMaps, RescaleRefusesABadFactorAndFloorSourceIsSetBeforeKeyFrames)
{
	sfm::SparseMap map;
	auto maps = gridMaps();
	EXPECT_THROW(maps->applyRescale(map, 0.0, Eigen::Vector3d(0, 0, 1), 0.0), std::invalid_argument);
	EXPECT_THROW(maps->applyRescale(map, std::nan(""), Eigen::Vector3d(0, 0, 1), 0.0), std::invalid_argument);
	mrpt::config::CConfigFileMemory ini("[MappingApplication]\nismOccupancyGrid2D_count = 1\n");
	slam::MetricMaps late(ini, slam::MapFeedOptions{});
	late.insertKeyFrame(map, addKeyFrame(map, 0), 0.0);
	EXPECT_THROW(late.useFloorFromCameraHeight(), std::logic_error);
}
}  // namespace monocular_maps_unittest

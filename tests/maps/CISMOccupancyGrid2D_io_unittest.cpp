/** CISMOccupancyGrid2D serialization round trip, ROS map_server export re-read by MRPT, PNG,
 * conversion to COccupancyGridMap2D and the 3D visualization. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <gtest/gtest.h>

#include <random>

#include "ISMSyntheticRoom.h"
#include "TestData.h"

using keygrid::CellState;
using keygrid::CISMOccupancyGrid2D;

namespace
{
/** A room mapped from 8 sparse keyframes. */
CISMOccupancyGrid2D mappedRoom()
{
	keygrid::test::SyntheticRoom room;
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	std::mt19937 rng(5);
	for (int k = 0; k < 8; k++)
	{
		const auto T = room.cameraPose(0.2, -0.1, 1.0, k * M_PI / 4, 0.25);
		grid.insertKeyframePoints(static_cast<uint64_t>(k), T, room.samplePoints(T, 300, 0.01, rng));
	}
	return grid;
}
}  // namespace

TEST(CISMOccupancyGrid2D_io, SerializationRoundTrip)
{
	CISMOccupancyGrid2D a = mappedRoom();
	a.insertionOptions.rayTraversal = CISMOccupancyGrid2D::RayTraversal::AntiAliased;
	a.insertionOptions.pOccupied = 0.83;
	a.insertionOptions.T_world_floor = mrpt::poses::CPose3D(0.1, 0.2, 0.3, 0.4, 0.5, 0.6);
	a.likelihoodOptions.decimation = 3;
	mrpt::io::CMemoryStream buf;
	auto arch = mrpt::serialization::archiveFrom(buf);
	arch << a;
	buf.Seek(0);
	mrpt::serialization::CSerializable::Ptr obj;
	arch >> obj;
	const auto b = std::dynamic_pointer_cast<CISMOccupancyGrid2D>(obj);
	ASSERT_TRUE(b) << "deserialized object is not a keygrid::CISMOccupancyGrid2D";
	ASSERT_EQ(b->sizeX(), a.sizeX());
	ASSERT_EQ(b->sizeY(), a.sizeY());
	EXPECT_DOUBLE_EQ(b->xMin(), a.xMin());
	EXPECT_DOUBLE_EQ(b->resolution(), a.resolution());
	for (int cy = 0; cy < a.sizeY(); cy++)
		for (int cx = 0; cx < a.sizeX(); cx++) ASSERT_EQ(b->logOdds(cx, cy), a.logOdds(cx, cy));
	EXPECT_EQ(b->insertionOptions.rayTraversal, CISMOccupancyGrid2D::RayTraversal::AntiAliased);
	EXPECT_DOUBLE_EQ(b->insertionOptions.pOccupied, 0.83);
	EXPECT_EQ(b->likelihoodOptions.decimation, 3);
	EXPECT_NEAR(b->insertionOptions.T_world_floor.yaw(), 0.4, 1e-12);
	ASSERT_EQ(b->keyframes().size(), a.keyframes().size());
	EXPECT_EQ(b->keyframes().at(3).points_cam.size(), a.keyframes().at(3).points_cam.size());
	EXPECT_EQ(b->keyframes().at(3).points_cam[7].x, a.keyframes().at(3).points_cam[7].x);
	EXPECT_EQ(b->insertionOptions.freeSpaceModel, CISMOccupancyGrid2D::FreeSpaceModel::HeightBand);
	EXPECT_DOUBLE_EQ(b->insertionOptions.bandSliceHeight, a.insertionOptions.bandSliceHeight);
	// The height slices came along: one more keyframe gives the same grid in both.
	keygrid::test::SyntheticRoom room;
	std::mt19937 rng(9);
	const auto T = room.cameraPose(-0.5, 0.3, 1.0, 2.0, 0.3);
	const auto pts = room.samplePoints(T, 300, 0.01, rng);
	a.insertKeyframePoints(100, T, pts);
	b->insertKeyframePoints(100, T, pts);
	size_t changed = 0;
	for (int cy = 0; cy < a.sizeY(); cy++)
		for (int cx = 0; cx < a.sizeX(); cx++)
		{
			ASSERT_EQ(b->logOdds(cx, cy), a.logOdds(cx, cy)) << "cell " << cx << "," << cy;
			changed += a.logOdds(cx, cy) != 0.0f;
		}
	EXPECT_GT(changed, 100u);
}

TEST(CISMOccupancyGrid2D_io, UnknownSerializationVersionThrows)
{
	CISMOccupancyGrid2D a;
	mrpt::io::CMemoryStream buf;
	auto arch = mrpt::serialization::archiveFrom(buf);
	arch << a;
	// Object layout: class name, version byte, payload. Patch the version byte to 99.
	auto* bytes = static_cast<uint8_t*>(buf.getRawBufferData());
	const std::string name = "keygrid::CISMOccupancyGrid2D";
	size_t pos = std::string(reinterpret_cast<char*>(bytes), buf.getTotalBytesCount()).find(name);
	ASSERT_NE(pos, std::string::npos);
	bytes[pos + name.size()] = 99;
	buf.Seek(0);
	mrpt::serialization::CSerializable::Ptr obj;
	EXPECT_ANY_THROW(arch >> obj);
}

TEST(CISMOccupancyGrid2D_io, RosMapServerExportIsReadBackByMrpt)
{
	const CISMOccupancyGrid2D grid = mappedRoom();
	const auto n = grid.countStates();
	ASSERT_GT(n[2], 50u);
	ASSERT_GT(n[1], 200u);
	const std::string dir = keygrid::test::scratchDir("ism2d_mapserver");
	const std::string yaml = dir + "/map_2d.yaml";
	grid.saveAsRosMapServer(yaml);
	ASSERT_TRUE(mrpt::system::fileExists(dir + "/map_2d.pgm"));

	mrpt::maps::COccupancyGridMap2D mrptGrid;
	ASSERT_TRUE(mrptGrid.loadFromROSMapServerYAML(yaml));
	EXPECT_NEAR(mrptGrid.getResolution(), grid.resolution(), 1e-6);
	size_t compared = 0;
	for (int cy = 0; cy < grid.sizeY(); cy++)
		for (int cx = 0; cx < grid.sizeX(); cx++)
		{
			const float pFree = mrptGrid.getPos(static_cast<float>(grid.idx2x(cx)), static_cast<float>(grid.idx2y(cy)));
			const CellState s = grid.cellState(cx, cy);
			// MRPT cells hold p(free): occupied < 0.35, free > 0.65, unknown ~ 0.5.
			const CellState back = pFree < 0.35f ? CellState::Occupied : pFree > 0.65f ? CellState::Free : CellState::Unknown;
			ASSERT_EQ(static_cast<int>(back), static_cast<int>(s)) << "cell " << cx << "," << cy << " pFree=" << pFree;
			compared++;
		}
	EXPECT_EQ(compared, static_cast<size_t>(grid.sizeX()) * grid.sizeY());
}

TEST(CISMOccupancyGrid2D_io, ConversionToCOccupancyGridMap2DAndImage)
{
	const CISMOccupancyGrid2D grid = mappedRoom();
	const auto g = grid.toOccupancyGridMap2D();
	EXPECT_EQ(static_cast<int>(g.getSizeX()), grid.sizeX());
	EXPECT_EQ(static_cast<int>(g.getSizeY()), grid.sizeY());
	for (int cy = 0; cy < grid.sizeY(); cy += 3)
		for (int cx = 0; cx < grid.sizeX(); cx += 3)
			// MRPT quantizes log-odds to int8 steps: allow a small difference.
			ASSERT_NEAR(1.0 - g.getCell(cx, cy), grid.occupancy(cx, cy), 0.02) << cx << "," << cy;

	const std::string dir = keygrid::test::scratchDir("ism2d_png");
	grid.saveAsImage(dir + "/map_2d.png");
	mrpt::img::CImage img;
	ASSERT_TRUE(img.loadFromFile(dir + "/map_2d.png"));
	EXPECT_EQ(static_cast<int>(img.getWidth()), grid.sizeX());
	grid.saveMetricMapRepresentationToFile(dir + "/prefix");
	EXPECT_TRUE(mrpt::system::fileExists(dir + "/prefix.yaml"));
	EXPECT_TRUE(mrpt::system::fileExists(dir + "/prefix.png"));

	mrpt::opengl::CSetOfObjects scene;
	grid.getVisualizationInto(scene);
	EXPECT_EQ(scene.size(), 1u);
	EXPECT_FALSE(grid.isEmpty());
	EXPECT_NE(grid.asString().find("keyframes=8"), std::string::npos) << grid.asString();
}

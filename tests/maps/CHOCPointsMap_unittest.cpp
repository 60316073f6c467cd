/** \file CHOCPointsMap_unittest.cpp
 * CHOCPointsMap: INI creation through CMultiMetricMap, serialization round trip, depth-scan
 * updates (a vanished object's points are pruned, static and occluded points stay), PLY. */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CHOCPointsMap.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <gtest/gtest.h>

#include "../TestData.h"
#include "ArchiveRoundTrip.h"

#include <cmath>

using keygrid::CHOCPointsMap;

namespace
{
/** A depth scan of the camera at the origin looking along +z (optical), the world frame being
 * the optical frame: a wall at z = 3 m, and optionally a box face at z = 1.5 m covering the
 * pixel columns [200, 400) and rows [150, 350). */
mrpt::obs::CObservation3DRangeScan::Ptr scan(bool box, bool nearBox = false)
{
	const auto cam = keygrid::core::RgbdCamera::Preset("kinect");
	auto obs = mrpt::obs::CObservation3DRangeScan::Create();
	obs->hasRangeImage = true;
	obs->range_is_depth = true;
	obs->rangeUnits = cam.depthUnits;
	obs->rangeImage.resize(cam.height, cam.width);
	for (unsigned r = 0; r < cam.height; r++)
		for (unsigned c = 0; c < cam.width; c++)
		{
			double z = 3.0;
			if (box && c >= 200 && c < 400 && r >= 150 && r < 350) z = 1.5;
			if (nearBox && c >= 100 && c < 500 && r >= 100 && r < 400) z = 1.0;
			obs->rangeImage(r, c) = static_cast<uint16_t>(std::lround(z / cam.depthUnits));
		}
	obs->cameraParams = cam.toTCamera();
	obs->cameraParamsIntensity = obs->cameraParams;
	obs->relativePoseIntensityWRTDepth = keygrid::core::T_depth_cam();
	return obs;
}

void insert(CHOCPointsMap& m, const mrpt::obs::CObservation3DRangeScan& o)
{
	m.insertObservation(o, mrpt::poses::CPose3D(keygrid::core::sensorPoseFromCameraPose(mrpt::poses::CPose3D())));
}

std::size_t countNear(const CHOCPointsMap& m, double z)
{
	std::size_t n = 0;
	for (const auto& p : m.points()) n += std::abs(p.p.z - z) < 0.02;
	return n;
}
}  // namespace

TEST(CHOCPointsMap, CreatedFromIniThroughCMultiMetricMap)
{
	mrpt::config::CConfigFileMemory cfg(std::string(R"(
[map]
hocPointsMap_count = 1
[map_hocPointsMap_00_creationOpts]
radii = 0.5 1 2
subdivisions = 1
prune_threshold = 0.55
[map_hocPointsMap_00_insertOpts]
point_spacing = 0.1
decimation = 4
)"));
	mrpt::maps::TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(cfg, "map");
	mrpt::maps::CMultiMetricMap mm;
	mm.setListOfMaps(inits);
	const auto m = mm.mapByClass<CHOCPointsMap>();
	ASSERT_TRUE(m) << "hocPointsMap was not created";
	EXPECT_EQ(m->geometry().numBins(), 3 * 80);
	EXPECT_DOUBLE_EQ(m->hocOptions.pruneThreshold, 0.55);
	EXPECT_DOUBLE_EQ(m->insertionOptions.pointSpacing, 0.1);
	EXPECT_EQ(m->insertionOptions.decimation, 4);
}

TEST(CHOCPointsMap, SerializationRoundTripKeepsPointsDescriptorsAndHistograms)
{
	keygrid::maps::HocOptions o;
	o.radii = {0.7, 3.0};
	o.countLimit = 7;
	o.decrementNeedsKeypoint = true;  // not the default: checks that version 1 stores it
	CHOCPointsMap m(o);
	std::vector<CHOCPointsMap::Point> pts;
	for (int i = 0; i < 50; i++)
	{
		CHOCPointsMap::Point p;
		p.id = 100 + i;
		p.p = {0.1 * i, -0.2 * i, 1.0 + 0.01 * i};
		p.descriptor.assign(32, static_cast<uint8_t>(i));
		if (i % 3) p.hoc.add(i % 40, (i % 2) ? 3 : -2, o.countLimit, 40);
		pts.push_back(p);
	}
	m.setPoints(pts);
	const CHOCPointsMap back = keygrid::test::archiveRoundTrip(m);
	ASSERT_EQ(back.size(), 50u);
	EXPECT_EQ(back.hocOptions.radii, o.radii);
	EXPECT_EQ(back.hocOptions.countLimit, 7);
	EXPECT_TRUE(back.hocOptions.decrementNeedsKeypoint);
	for (std::size_t i = 0; i < 50; i++)
	{
		EXPECT_EQ(back.points()[i].id, pts[i].id);
		EXPECT_DOUBLE_EQ(back.points()[i].p.y, pts[i].p.y);
		EXPECT_EQ(back.points()[i].descriptor, pts[i].descriptor);
		EXPECT_EQ(back.points()[i].hoc.counts(), pts[i].hoc.counts());
	}
	// Wrong number of bins is refused.
	CHOCPointsMap::Point bad;
	bad.hoc.add(0, 1, 5, 20);
	EXPECT_THROW(m.setPoints({bad}), std::invalid_argument);
}

TEST(CHOCPointsMap, VanishedObjectIsPrunedStaticAndOccludedPointsStay)
{
	CHOCPointsMap m;
	insert(m, *scan(true));
	const std::size_t boxPts = countNear(m, 1.5), wallPts = countNear(m, 3.0);
	ASSERT_GT(boxPts, 100u);
	ASSERT_GT(wallPts, 500u);
	// The box is gone: the camera sees the wall through where its points were. Each scan
	// subtracts one from their bin: +1 - 1 = 0, weight 0.5 < prune threshold 0.6 (and every
	// other bin is 0 too).
	insert(m, *scan(false));
	EXPECT_EQ(countNear(m, 1.5), 0u) << "points of the vanished box must be pruned";
	const std::size_t wallAfter = countNear(m, 3.0);
	EXPECT_GE(wallAfter, wallPts);  // wall points kept, new ones where the box hid the wall
	// Something comes close and hides part of the wall for many scans: occluded points are
	// not penalised, so none of the wall points is lost.
	for (int i = 0; i < 5; i++) insert(m, *scan(false, true));
	EXPECT_EQ(countNear(m, 3.0), wallAfter);
	const auto path = keygrid::test::scratchDir("hoc_points_map") + "/hoc";
	m.saveMetricMapRepresentationToFile(path);
	const std::string ply = keygrid::test::readTextFile(path + ".ply");
	EXPECT_NE(ply.find("element vertex " + std::to_string(m.size()) + "\n"), std::string::npos);
}

/** CSubmappedOccupancyGrid3D as an MRPT plugin: serialization round trip, unknown versions,
 * creation from an INI through CMultiMetricMap, OctoMap .bt export re-read with OcTree, PLY,
 * visualization, and insertObservation() of the real Kinect frame of tests_rgbd.rawlog. */
#include "Grid3DTestScenes.h"
#include "MapIniChecks.h"
#include "TestData.h"

#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <octomap/OcTree.h>
#include <opencv2/core.hpp>

#include <fstream>
#include <sstream>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
/** A map with two submaps (a forced conflict), stored depth and non-default options. */
CSubmappedOccupancyGrid3D twoSubmapMap()
{
	auto m = test::mapOfWall([](CSubmappedOccupancyGrid3D& g) {
		g.insertionOptions.storeKeyframeDepth = true;
		g.insertionOptions.integration.logOddsHit = 0.9f;
		g.morphingOptions.weightExponent = 3.0;
		g.morphingOptions.interpolation = MorphingOptions::Interpolation::Nearest;
		g.morphingOptions.maxKeyframesPerBlock = 12;
		g.likelihoodOptions.decimation = 7;
	});
	const auto cam = test::smallCamera();
	m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(0, 0, 0.5, 0.1, 0, 0), 5.0, 3);
	return m;
}

struct Probe : public CSubmappedOccupancyGrid3D
{
	void read(mrpt::serialization::CArchive& a, uint8_t v) { serializeFrom(a, v); }
};
}  // namespace

TEST(SubmappedIo, SerializationRoundTrip)
{
	const auto m = twoSubmapMap();
	ASSERT_EQ(m.numSubmaps(), 2u);
	mrpt::io::CMemoryStream buf;
	auto arch = mrpt::serialization::archiveFrom(buf);
	arch << m;
	buf.Seek(0);
	const auto obj = arch.ReadObject();
	const auto r = std::dynamic_pointer_cast<CSubmappedOccupancyGrid3D>(obj);
	ASSERT_TRUE(r);
	EXPECT_EQ(r->resolution(), m.resolution());
	ASSERT_EQ(r->numSubmaps(), 2u);
	EXPECT_EQ(r->activeSubmap(), 1u);
	EXPECT_EQ(r->mode(), m.mode());
	for (std::size_t i = 0; i < 2; ++i)
	{
		EXPECT_TRUE(r->submap(i).grid == m.submap(i).grid) << i;
		EXPECT_EQ(r->submap(i).keyframes, m.submap(i).keyframes);
		EXPECT_EQ(r->submap(i).anchorKeyframe, m.submap(i).anchorKeyframe);
	}
	ASSERT_EQ(r->keyframes().size(), 3u);
	for (const auto& [id, k] : m.keyframes())
	{
		const auto& q = r->keyframes().at(id);
		EXPECT_EQ(q.T_world_cam.asString(), k.T_world_cam.asString());
		EXPECT_EQ(q.travelled, k.travelled);
		EXPECT_EQ(q.submap, k.submap);
		EXPECT_EQ(q.camera.fx, k.camera.fx);
		EXPECT_EQ(q.camera.width, k.camera.width);
		ASSERT_EQ(q.depth.size(), k.depth.size());
		EXPECT_EQ(cv::norm(q.depth, k.depth, cv::NORM_INF), 0.0);
	}
	EXPECT_EQ(r->insertionOptions.integration.logOddsHit, 0.9f);
	EXPECT_TRUE(r->insertionOptions.storeKeyframeDepth);
	EXPECT_EQ(r->insertionOptions.conflict.conflictMinVoxels, 100);
	EXPECT_EQ(r->morphingOptions.weightExponent, 3.0);
	EXPECT_EQ(r->morphingOptions.interpolation, MorphingOptions::Interpolation::Nearest);
	EXPECT_EQ(r->morphingOptions.maxKeyframesPerBlock, 12u);
	EXPECT_EQ(r->likelihoodOptions.decimation, 7u);

	Probe p;
	buf.Seek(0);
	EXPECT_ANY_THROW(p.read(arch, 4));  // a version this build does not know
}

TEST(SubmappedIo, CreatedFromIniThroughCMultiMetricMap)
{
	const std::string ini = R"(
[map]
submappedOccupancyGrid3D_count=1
[map_submappedOccupancyGrid3D_00_creationOpts]
resolution=0.1
[map_submappedOccupancyGrid3D_00_insertOpts]
maxRange=3.5
pixelDecimation=2
travelledDistanceThreshold=2.5
storeKeyframeDepth=true
morphWeightExponent=3
morphInterpolation=nearest
[map_submappedOccupancyGrid3D_00_likelihoodOpts]
decimation=5
)";
	mrpt::config::CConfigFileMemory cfg(ini);
	mrpt::maps::TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(cfg, "map");
	ASSERT_EQ(inits.size(), 1u);
	mrpt::maps::CMultiMetricMap mm;
	mm.setListOfMaps(inits);
	const auto m = mm.mapByClass<CSubmappedOccupancyGrid3D>();
	ASSERT_TRUE(m) << "submappedOccupancyGrid3D was not created";
	EXPECT_DOUBLE_EQ(m->resolution(), 0.1);
	EXPECT_DOUBLE_EQ(m->insertionOptions.integration.maxRange, 3.5);
	EXPECT_EQ(m->insertionOptions.integration.pixelDecimation, 2u);
	EXPECT_DOUBLE_EQ(m->insertionOptions.conflict.travelledDistanceThreshold, 2.5);
	EXPECT_TRUE(m->insertionOptions.storeKeyframeDepth);
	EXPECT_DOUBLE_EQ(m->morphingOptions.weightExponent, 3.0);
	EXPECT_EQ(m->morphingOptions.interpolation, MorphingOptions::Interpolation::Nearest);
	EXPECT_EQ(m->likelihoodOptions.decimation, 5u);

	// Options save / load round trip and errors naming the key.
	mrpt::config::CConfigFileMemory out;
	m->insertionOptions.saveToConfigFile(out, "ins");
	CSubmappedOccupancyGrid3D::TInsertionOptions back;
	back.loadFromConfigFile(mrpt::config::CConfigFileMemory(out.getContent()), "ins");  // through the INI text
	EXPECT_DOUBLE_EQ(back.integration.maxRange, 3.5);
	EXPECT_TRUE(back.storeKeyframeDepth);
	// (Through the map definition directly: TSetOfMetricMapInitializers leaks the initializer
	// it was filling when loading throws, which LeakSanitizer reports.)
	mrpt::config::CConfigFileMemory bad(
		"[map_submappedOccupancyGrid3D_00_insertOpts]\nmaxRange=four\n");
	CSubmappedOccupancyGrid3D::TMapDefinition def;
	try
	{
		def.loadFromConfigFile(bad, "map_submappedOccupancyGrid3D_00");
		FAIL() << "a non-numeric maxRange must throw";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("maxRange"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("four"), std::string::npos) << e.what();
	}
	mrpt::config::CConfigFileMemory badInterp(
		"[map_submappedOccupancyGrid3D_00_insertOpts]\nmorphInterpolation=cubic\n");
	try
	{
		def.loadFromConfigFile(badInterp, "map_submappedOccupancyGrid3D_00");
		FAIL() << "an unknown morphInterpolation must throw";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("morphInterpolation"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("cubic"), std::string::npos) << e.what();
	}
}

// A bad value in any of the grid's INI sections throws naming that section and the key; MRPT's
// yes/no booleans are still read.
TEST(SubmappedIo, BadIniValueNamesSectionAndKey)
{
	const std::string prefix = "map_submappedOccupancyGrid3D_00";
	keygrid::test::expectBadValuesNameSectionAndKey<CSubmappedOccupancyGrid3D::TMapDefinition>(
		prefix, {
			{"_creationOpts", "resolution = 0"},
			{"_insertOpts", "minRange = 5"},
			{"_insertOpts", "logOddsMiss = 0.1"},
			{"_insertOpts", "maxDenseMarkVoxels = 100"},
			{"_insertOpts", "localizationExitHitFraction = 1.5"},
			{"_insertOpts", "storeKeyframeDepth = maybe"},
			{"_insertOpts", "morphInterpolation = cubic"},
			{"_likelihoodOpts", "minProbability = 0.5"}});
	mrpt::config::CConfigFileMemory ini("[" + prefix + "_insertOpts]\nstoreKeyframeDepth = yes\ndiscretizeEndpoints = no\n");
	CSubmappedOccupancyGrid3D::TMapDefinition def;
	def.loadFromConfigFile(ini, prefix);
	EXPECT_TRUE(def.insertionOpts.storeKeyframeDepth);
	EXPECT_FALSE(def.insertionOpts.integration.discretizeEndpoints);
}

TEST(SubmappedIo, OctomapExportAgreesVoxelByVoxel)
{
	CSubmappedOccupancyGrid3D m(0.05);
	const auto cam = test::smallCamera(80, 60, 70);
	const CPose3D T(0.1, -0.05, 0.2, 0.3, 0.1, -0.05);
	m.insertDepthFrame(test::boxRoomDepth(cam, T, {-2, -1.5, -1}, {2.5, 1.5, 3}), cam, T, 0.0, 0);
	const std::string dir = test::scratchDir("grid3d_export");
	m.saveMetricMapRepresentationToFile(dir + "/room");
	ASSERT_TRUE(mrpt::system::fileExists(dir + "/room.bt"));

	octomap::OcTree tree(dir + "/room.bt");
	ASSERT_DOUBLE_EQ(tree.getResolution(), 0.05);
	const auto& g = m.submap(0).grid;
	std::size_t occ = 0, free = 0, bad = 0;
	g.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		const octomap::OcTreeKey key(v.x + 32768, v.y + 32768, v.z + 32768);
		const octomap::OcTreeNode* n = tree.search(key);
		if (!n || tree.isNodeOccupied(n) != (x.logOdds > 0)) ++bad;
		(x.logOdds > 0 ? occ : free)++;
	});
	EXPECT_EQ(bad, 0u);
	// Volume of the tree's occupied / free leaves, in voxels, equals ours (no extra voxels).
	double treeOcc = 0, treeFree = 0;
	for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
	{
		const double n = std::pow(2.0, 16 - int(it.getDepth()));
		(tree.isNodeOccupied(*it) ? treeOcc : treeFree) += n * n * n;
	}
	EXPECT_EQ(treeOcc, double(occ));
	EXPECT_EQ(treeFree, double(free));

	// PLY: one vertex per occupied voxel.
	std::ifstream ply(dir + "/room_occupied.ply");
	std::string line;
	std::size_t declared = 0, rows = 0;
	bool body = false;
	while (std::getline(ply, line))
	{
		if (body) ++rows;
		else if (line.rfind("element vertex ", 0) == 0) declared = std::stoul(line.substr(15));
		else if (line == "end_header") body = true;
	}
	EXPECT_EQ(declared, occ);
	EXPECT_EQ(rows, occ);

	// Visualization: the occupied voxel centres as a point cloud.
	mrpt::opengl::CSetOfObjects scene;
	m.getVisualizationInto(scene);
	const auto pc = scene.getByClass<mrpt::opengl::CPointCloud>();
	ASSERT_TRUE(pc);
	EXPECT_EQ(pc->size(), occ);

	// The .3Dscene re-loads with the same point cloud (SceneViewer3D reads this file).
	mrpt::opengl::COpenGLScene loaded;
	ASSERT_TRUE(loaded.loadFromFile(dir + "/room.3Dscene"));
	const auto set = loaded.getByClass<mrpt::opengl::CSetOfObjects>();
	ASSERT_TRUE(set);
	const auto pc2 = set->getByClass<mrpt::opengl::CPointCloud>();
	ASSERT_TRUE(pc2);
	EXPECT_EQ(pc2->size(), occ);

	// clone() (used by CMultiMetricMap copies) is a deep copy.
	std::unique_ptr<mrpt::rtti::CObject> c(m.clone());
	const auto* cm = dynamic_cast<const CSubmappedOccupancyGrid3D*>(c.get());
	ASSERT_TRUE(cm);
	EXPECT_TRUE(cm->submap(0).grid == g);
}

TEST(SubmappedIo, ExportsInAnotherFrameResampledAndRecorded)
{
	// keygrid-slam writes map_3d.bt / .ply in the floor frame: a rigid change of frame with a
	// metadata line. The .bt is resampled at the same resolution (nearest neighbour).
	CSubmappedOccupancyGrid3D m(0.05);
	const auto cam = test::smallCamera(80, 60, 70);
	const CPose3D T(0.1, -0.05, 0.2, 0.3, 0.1, -0.05);
	m.insertDepthFrame(test::boxRoomDepth(cam, T, {-2, -1.5, -1}, {2.5, 1.5, 3}), cam, T, 0.0, 0);
	const CPose3D T_world_floor(0.2, 1.1, -0.3, 0.4, -0.2, 1.2);
	const auto frame = maps::floorExportFrame(T_world_floor);
	const std::string dir = test::scratchDir("grid3d_export_frame");
	m.saveAsOctomapBinary(dir + "/floor.bt", frame);
	m.saveOccupiedAsPly(dir + "/floor.ply", frame);

	// OctoMap's reader takes the comment line (AbstractOcTree::readHeader skips '#' lines).
	{
		std::ifstream f(dir + "/floor.bt");
		std::string first, second;
		std::getline(f, first);
		std::getline(f, second);
		EXPECT_EQ(first.rfind("# Octomap OcTree binary file", 0), 0u) << first;
		EXPECT_EQ(second, "# " + frame.comment);
	}
	octomap::OcTree tree(0.1);
	ASSERT_TRUE(tree.readBinary(dir + "/floor.bt"));
	ASSERT_DOUBLE_EQ(tree.getResolution(), 0.05);
	// Every leaf of the output lattice has the state of the world voxel holding its centre,
	// and the lattice holds as many voxels as the world grid, within the resampling's few %.
	const auto& g = m.submap(0).grid;
	std::size_t leaves = 0, bad = 0, known = 0;
	g.forEachKnown([&](const VoxelIndex&, const Voxel&) { ++known; });
	tree.expand();
	for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
	{
		++leaves;
		const auto c = it.getCoordinate();
		const auto w = T_world_floor.composePoint(mrpt::math::TPoint3D(c.x(), c.y(), c.z()));
		const Voxel* v = g.find(g.voxelOf(w));
		if (!v || !v->isKnown() || (v->logOdds > 0) != tree.isNodeOccupied(*it)) ++bad;
	}
	EXPECT_EQ(bad, 0u);
	EXPECT_NEAR(static_cast<double>(leaves) / known, 1.0, 0.05);

	// The PLY: the occupied centres moved exactly, with the same comment.
	std::ifstream ply(dir + "/floor.ply");
	std::string line;
	bool body = false, commented = false;
	std::vector<mrpt::math::TPoint3D> pts;
	while (std::getline(ply, line))
	{
		if (body)
		{
			std::istringstream is(line);
			double x, y, z;
			is >> x >> y >> z;
			pts.emplace_back(x, y, z);
		}
		else if (line == "comment " + frame.comment) commented = true;
		else if (line == "end_header") body = true;
	}
	EXPECT_TRUE(commented);
	const auto centres = m.occupiedVoxelCentres();
	ASSERT_EQ(pts.size(), centres.size());
	double worst = 0;
	for (std::size_t i = 0; i < pts.size(); i++) worst = std::max(worst, (T_world_floor.composePoint(pts[i]) - centres[i]).norm());
	EXPECT_LT(worst, 1e-5);
}

TEST(SubmappedIo, InsertsTheRealKinectFrameOfTestsRgbdRawlog)
{
	const std::string path = test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!mrpt::system::fileExists(path)) GTEST_SKIP() << path << " missing (package mrpt-common)";
	mrpt::obs::CRawlog rawlog;
	ASSERT_TRUE(rawlog.loadFromRawLogFile(path));
	mrpt::obs::CObservation3DRangeScan::Ptr obs;
	for (std::size_t i = 0; i < rawlog.size() && !obs; ++i)
		if (rawlog.getType(i) == mrpt::obs::CRawlog::etObservation)
			obs = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(rawlog.getAsObservation(i));
		else if (rawlog.getType(i) == mrpt::obs::CRawlog::etSensoryFrame)
			obs = rawlog.getAsObservations(i)->getObservationByClass<mrpt::obs::CObservation3DRangeScan>();
	ASSERT_TRUE(obs);
	obs->load();

	CSubmappedOccupancyGrid3D m(0.05);
	const CPose3D robot(0.5, -0.2, 0.3, 0.4, 0.0, 0.0);
	ASSERT_TRUE(m.insertObservation(*obs, robot));
	EXPECT_EQ(m.keyframes().size(), 1u);
	EXPECT_GT(m.submap(0).grid.numOccupiedVoxels(), 1000u);

	// Independent projection (MRPT's own unprojection, sensorPose included): the measured
	// points within range must fall into occupied voxels. MRPT's unprojection ignores the
	// depth camera's small distortion (k1 = -0.005) that keygrid removes: a few points differ.
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	obs->unprojectInto(pts, pp);
	std::size_t n = 0, inOccupied = 0;
	const auto sensor = (robot + obs->sensorPose).asTPose();
	for (std::size_t i = 0; i < pts.size(); ++i)
	{
		mrpt::math::TPoint3D p;
		pts.getPoint(i, p.x, p.y, p.z);
		const auto pw = robot.composePoint(p);
		const double r = std::sqrt(
			(pw.x - sensor.x) * (pw.x - sensor.x) + (pw.y - sensor.y) * (pw.y - sensor.y) +
			(pw.z - sensor.z) * (pw.z - sensor.z));
		if (r < 0.2 || r > 3.9) continue;
		++n;
		const auto L = m.logOddsAt(pw);
		inOccupied += (L && *L > 0) ? 1 : 0;
	}
	ASSERT_GT(n, 10000u);
	EXPECT_GT(double(inOccupied) / n, 0.95) << inOccupied << " of " << n;

	// The likelihood of the same observation is higher at the true pose than 30 cm off.
	const double atTrue = m.computeObservationLikelihood(*obs, robot);
	const double off = m.computeObservationLikelihood(*obs, robot + CPose3D(0.3, 0, 0, 0, 0, 0));
	EXPECT_GT(atTrue, off);
}

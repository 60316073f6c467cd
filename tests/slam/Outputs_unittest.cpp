// keygrid-slam's outputs for MRPT's tools: keyframes.simplemap rebuilt into the 3D
// grid by MRPT's observations2map with the plugin preloaded, scene.3Dscene loaded back, and
// rawlog-edit loading libkeygrid_maps.so. One short synthetic run (keygrid-sim room_arc cut
// to 40 frames, keygrid-slam config/sim.ini) feeds every test.
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/poses/CPose3DQuat.h>
#include <keygrid/maps/CHOCPointsMap.h>
#include <octomap/OcTree.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/CDirectoryExplorer.h>
#include <mrpt/system/filesystem.h>

#include "SimSlamRun.h"
#include <nlohmann/json.hpp>

#include "TestData.h"

#include <algorithm>
#include <fstream>
#include <optional>
#include <sstream>
#include <map>
#include <regex>
#include <set>
#include <tuple>

using namespace keygrid;

namespace
{
constexpr std::size_t kFrames = 40;

/** Generates the sequence and runs keygrid-slam on it into a folder of the calling test's own
 * (ctest runs each test in its own process, possibly in parallel). Returns the output
 * folder, "" after reporting a failure. */
std::string runSlamOnShortSimSequence()
{
	const std::string dir = test::scratchDir(std::string("outputs_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
	const auto run = test::renderAndRunSlam(
		dir, "--scene " + test::dataDir() + "/sim/room_arc.ini --frames 40 --voxel-resolution 0 --floorplan-resolution 0", false);
	if (!run.rendered)
	{
		ADD_FAILURE() << run.simLog;
		return "";
	}
	const auto& o = run.options;
	const auto& r = run.result;
	if (!r.error.empty() || r.frames != kFrames)
	{
		ADD_FAILURE() << "keygrid-slam: " << r.error << " (" << r.frames << " frames)";
		return "";
	}
	return o.output;
}

/** Vertices of an ASCII PLY point cloud (x y z first on each line); empty if the file holds
 * fewer vertices than its header says. */
std::vector<mrpt::math::TPoint3D> plyPoints(const std::string& path)
{
	std::ifstream f(path);
	std::string line;
	std::size_t n = 0;
	while (std::getline(f, line) && line != "end_header")
		if (line.rfind("element vertex ", 0) == 0) n = std::stoul(line.substr(15));
	std::vector<mrpt::math::TPoint3D> pts;
	double x, y, z;
	for (std::size_t i = 0; i < n && (f >> x >> y >> z); i++)
	{
		std::getline(f, line);  // rest of the vertex line (colour, if any)
		pts.emplace_back(x, y, z);
	}
	if (pts.size() != n) pts.clear();
	return pts;
}

/** Voxel-index triples of points at `resolution` (voxel centres -> their voxel). */
std::set<std::tuple<long, long, long>> voxelsOf(const std::vector<mrpt::math::TPoint3D>& pts, double resolution)
{
	std::set<std::tuple<long, long, long>> v;
	for (const auto& p : pts)
		v.emplace(std::lround(std::floor(p.x / resolution)), std::lround(std::floor(p.y / resolution)), std::lround(std::floor(p.z / resolution)));
	return v;
}

template <typename T>
void loadGz(const std::string& path, T& obj)
{
	mrpt::io::CFileGZInputStream f(path);
	mrpt::serialization::archiveFrom(f) >> obj;
}

/** The 7 numbers "x y z qx qy qz qw" after `key` (JSON array or space separated). */
std::optional<mrpt::poses::CPose3D> poseAfter(const std::string& text, const std::string& key)
{
	const auto at = text.find(key);
	if (at == std::string::npos) return std::nullopt;
	std::string rest = text.substr(at + key.size(), 300);
	for (auto& c : rest)
		if (c == '[' || c == ']' || c == ',') c = ' ';
	std::istringstream is(rest);
	double x, y, z, qx, qy, qz, qw;
	if (!(is >> x >> y >> z >> qx >> qy >> qz >> qw)) return std::nullopt;
	return mrpt::poses::CPose3D(mrpt::poses::CPose3DQuat(x, y, z, mrpt::math::CQuaternionDouble(qw, qx, qy, qz)));
}

/** report.json's floor frame ("floor": {..., "T_world_floor": [x y z qx qy qz qw]}). */
std::optional<mrpt::poses::CPose3D> reportFloorPose(const std::string& report)
{
	const auto at = report.find("\"floor\": {");
	if (at == std::string::npos) return std::nullopt;
	return poseAfter(report.substr(at), "\"T_world_floor\": ");
}

/** The share of `v` below `q`-quantile: the q-quantile of the values. */
double quantile(std::vector<double> v, double q)
{
	std::sort(v.begin(), v.end());
	return v.empty() ? 0.0 : v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

void expectNoTemporaryFiles(const std::string& out)
{
	for (const char* f : {"trajectory.txt", "keyframes.txt", "keyframes.simplemap", "scene.3Dscene", "report.json", "map_3d.ply"})
		EXPECT_TRUE(mrpt::system::fileExists(out + "/" + f)) << f;
	mrpt::system::CDirectoryExplorer::TFileInfoList files;
	mrpt::system::CDirectoryExplorer::explore(out, FILE_ATTRIB_ARCHIVE, files);
	for (const auto& fi : files) EXPECT_NE(mrpt::system::extractFileExtension(fi.name), "tmp") << fi.name;
}

void checkSimpleMap(const std::string& out)
{
	const auto kfs = core::readTumTrajectory(out + "/keyframes.txt");
	mrpt::maps::CSimpleMap sm;
	loadGz(out + "/keyframes.simplemap", sm);
	ASSERT_EQ(sm.size(), kfs.size());
	ASSERT_GE(sm.size(), 2u);
	for (std::size_t i = 0; i < sm.size(); i++)
	{
		const auto [pdf, sf] = sm.get(i);
		ASSERT_TRUE(pdf && sf);
		ASSERT_TRUE(IS_CLASS(*pdf, mrpt::poses::CPose3DPDFGaussian));
		const mrpt::poses::CPose3D T_world_robot = pdf->getMeanVal();
		auto obs = sf->getObservationByClass<mrpt::obs::CObservation3DRangeScan>();
		ASSERT_TRUE(obs);
		ASSERT_TRUE(obs->hasRangeImage && obs->hasIntensityImage);
		EXPECT_EQ(obs->intensityImage.getChannelCount(), 3u);  // the sim renders colour
		EXPECT_NEAR(mrpt::Clock::toDouble(obs->timestamp), kfs[i].t, 1e-3);

		// MRPT's own unprojection of the observation at the entry's pose must land every
		// depth pixel where keygrid's pinhole back-projection at T_world_cam (keyframes.txt,
		// written independently) puts it.
		mrpt::maps::CSimplePointsMap pts;
		mrpt::obs::T3DPointsProjectionParams pp;
		pp.takeIntoAccountSensorPoseOnRobot = true;
		pp.robotPoseInTheWorld = T_world_robot;
		pp.MAKE_ORGANIZED = true;
		obs->unprojectInto(pts, pp);
		const auto& K = obs->cameraParams;
		const int W = static_cast<int>(obs->rangeImage.cols()), H = static_cast<int>(obs->rangeImage.rows());
		ASSERT_EQ(pts.size(), static_cast<std::size_t>(W * H));
		std::size_t checked = 0;
		double worst = 0;
		for (int r = 0; r < H; r += 7)
			for (int c = 0; c < W; c += 7)
			{
				const double z = obs->rangeImage(r, c) * obs->rangeUnits;
				if (!(z > 0)) continue;
				const mrpt::math::TPoint3D p_cam((c - K.cx()) / K.fx() * z, (r - K.cy()) / K.fy() * z, z);
				const auto p = kfs[i].T_world_cam.composePoint(p_cam);
				mrpt::math::TPoint3D q;
				pts.getPoint(static_cast<std::size_t>(r * W + c), q);
				worst = std::max(worst, (p - q).norm());
				checked++;
			}
		EXPECT_GT(checked, 1000u);
		// keyframes.txt has 9 decimals; MRPT unprojects in float (~1e-7 x 4 m).
		EXPECT_LT(worst, 1e-4) << "keyframe " << i;
	}
}

void checkScene(const std::string& out)
{
	mrpt::opengl::COpenGLScene scene;
	loadGz(out + "/scene.3Dscene", scene);

	const auto traj = core::readTumTrajectory(out + "/trajectory.txt");
	ASSERT_EQ(traj.size(), kFrames);
	auto line = std::dynamic_pointer_cast<mrpt::opengl::CSetOfLines>(scene.getByName("trajectory"));
	ASSERT_TRUE(line);
	// A line strip: N poses -> N-1 segments, each starting where the previous one ended, at
	// the camera centres of trajectory.txt.
	ASSERT_EQ(line->getLineCount() + 1, traj.size());
	for (std::size_t i = 0; i < line->getLineCount(); i++)
	{
		double x0, y0, z0, x1, y1, z1;
		line->getLineByIndex(i, x0, y0, z0, x1, y1, z1);
		const auto& a = traj[i].T_world_cam;
		const auto& b = traj[i + 1].T_world_cam;
		EXPECT_NEAR(x0, a.x(), 1e-4);
		EXPECT_NEAR(y0, a.y(), 1e-4);
		EXPECT_NEAR(z0, a.z(), 1e-4);
		EXPECT_NEAR(x1, b.x(), 1e-4);
		EXPECT_NEAR(y1, b.y(), 1e-4);
		EXPECT_NEAR(z1, b.z(), 1e-4);
	}

	auto run = scene.getByName("keygrid_run");
	ASSERT_TRUE(run);
	const mrpt::poses::CPose3D T_display_world = run->getPoseRef();

	const auto kfs = core::readTumTrajectory(out + "/keyframes.txt");
	auto frustums = std::dynamic_pointer_cast<mrpt::opengl::CSetOfObjects>(scene.getByName("keyframes"));
	ASSERT_TRUE(frustums);
	std::size_t nFrustums = 0;
	for (const auto& o : *frustums) nFrustums += IS_CLASS(*o, mrpt::opengl::CFrustum);
	EXPECT_EQ(nFrustums, kfs.size());

	// One "map_<i>_<class>" set per map of the run (report.json lists them); the 3D grid's
	// occupied voxels are those of map_3d.ply.
	const std::string report = test::readTextFile(out + "/report.json");
	const auto reportMaps = nlohmann::json::parse(report)["maps"];
	std::map<std::string, mrpt::opengl::CSetOfObjects::Ptr> mapSets;  // class -> set
	for (const auto& o : *scene.getViewport())
		if (o->getName().rfind("map_", 0) == 0)
		{
			const std::string cls = o->getName().substr(o->getName().find('_', 4) + 1);
			EXPECT_TRUE(std::any_of(reportMaps.begin(), reportMaps.end(), [&](const auto& m) { return m["class"] == cls; })) << cls;
			mapSets[cls] = std::dynamic_pointer_cast<mrpt::opengl::CSetOfObjects>(o);
		}
	EXPECT_EQ(mapSets.size(), reportMaps.size());
	auto grid2d = mapSets["keygrid::CISMOccupancyGrid2D"];
	auto grid3d = mapSets["keygrid::CSubmappedOccupancyGrid3D"];
	ASSERT_TRUE(grid2d);
	ASSERT_TRUE(grid3d);
	ASSERT_FALSE(grid2d->empty());
	// The display frame is the 2D grid's floor frame: the grid (posed at T_world_floor in the
	// world) lands at the identity, i.e. on the display's z = 0 plane.
	const mrpt::poses::CPose3D gridPose = (*grid2d->begin())->getPoseRef();
	EXPECT_LT(gridPose.translation().norm(), 1e-9);
	EXPECT_LT((gridPose.getRotationMatrix() - mrpt::math::CMatrixDouble33::Identity()).norm(), 1e-9);
	auto voxels = grid3d->getByClass<mrpt::opengl::CPointCloud>();
	ASSERT_TRUE(voxels);
	// The same voxel centres as map_3d.ply (same order): both in the floor frame.
	const auto ply = plyPoints(out + "/map_3d.ply");
	EXPECT_GT(ply.size(), 1000u);
	ASSERT_EQ(voxels->size(), ply.size());
	double worst = 0;
	for (std::size_t k = 0; k < ply.size(); k++)
	{
		const auto& q = voxels->getPoint3Df(k);
		worst = std::max(worst, (ply[k] - mrpt::math::TPoint3D(q.x, q.y, q.z)).norm());
	}
	EXPECT_LT(worst, 1e-3);
	// The display frame is the run's floor frame of report.json.
	const auto T_world_floor = reportFloorPose(report);
	ASSERT_TRUE(T_world_floor);
	EXPECT_LT(((-*T_world_floor).asTPose() - T_display_world.asTPose()).norm(), 1e-6);
}
}  // namespace

TEST(Outputs, SimRunWritesSimplemapAndSceneThatMrptReads)
{
	const std::string out = runSlamOnShortSimSequence();
	ASSERT_FALSE(out.empty());
	{
		SCOPED_TRACE("outputs complete, no temporary file left");
		expectNoTemporaryFiles(out);
	}
	{
		SCOPED_TRACE("keyframes.simplemap");
		checkSimpleMap(out);
	}
	{
		SCOPED_TRACE("scene.3Dscene");
		checkScene(out);
	}
}

#if KEYGRID_TESTS_SANITIZED
#define KEYGRID_SKIP_IF_SANITIZED() \
	GTEST_SKIP() << "sanitized build: " KEYGRID_MAPS_LIBRARY " cannot be loaded into MRPT's uninstrumented tools"
#else
#define KEYGRID_SKIP_IF_SANITIZED() (void)0
#endif

TEST(Outputs, ObservationsToMapRebuildsThe3DGridFromKeyframesSimplemap)
{
	KEYGRID_SKIP_IF_SANITIZED();
	const std::string out = runSlamOnShortSimSequence();
	ASSERT_FALSE(out.empty());
	const std::string dir = mrpt::system::extractFileDirectory(out) + "/o2m";
	ASSERT_TRUE(mrpt::system::createDirectory(dir));
	// The 3D grid exactly as config/sim.ini configures it, alone.
	{
		std::ofstream ini(dir + "/o2m.ini");
		ini << "[MappingApplication]\nsubmappedOccupancyGrid3D_count = 1\n\n"
			   "[MappingApplication_submappedOccupancyGrid3D_00_creationOpts]\nresolution = 0.05\n\n"
			   "[MappingApplication_submappedOccupancyGrid3D_00_insertOpts]\nmaxRange = 4.0\n";
	}
	std::string log;
	ASSERT_EQ(test::runCommand("LD_PRELOAD=" KEYGRID_MAPS_LIBRARY " observations2map " + dir + "/o2m.ini " + out +
								   "/keyframes.simplemap " + dir + "/rebuilt < /dev/null", &log), 0) << log;
	const auto kfs = core::readTumTrajectory(out + "/keyframes.txt");
	EXPECT_NE(log.find("done: " + std::to_string(kfs.size()) + " observations"), std::string::npos) << log;
	// CMultiMetricMap names each map's files <prefix>_<class, ':' -> '_'>_<index>.
	const std::string rebuilt = dir + "/rebuilt_keygrid__CSubmappedOccupancyGrid3D_00_occupied.ply";
	ASSERT_TRUE(mrpt::system::fileExists(rebuilt)) << log;

	// Same keyframes, same options: the rebuilt grid must be keygrid-slam's own. They differ
	// only where keygrid-slam integrated a keyframe at its online pose before the final
	// refinement moved it (and in the travelled distance, from all frames vs. keyframes).
	// The bounds below (voxel counts within 10 %, Jaccard > 0.85) are empirical margins over the
	// agreement in doc/evaluation.md, "3D grid" (observations2map).
	// map_3d.ply is in the floor frame (its comment line), observations2map's in the world.
	auto ownPts = plyPoints(out + "/map_3d.ply");
	const auto rebuiltPts = plyPoints(rebuilt);
	const auto T_world_floor = poseAfter(test::readTextFile(out + "/map_3d.ply"), "comment keygrid T_world_floor (x y z qx qy qz qw): ");
	ASSERT_TRUE(T_world_floor);
	for (auto& p : ownPts) p = T_world_floor->composePoint(p);
	const auto own = voxelsOf(ownPts, 0.05), re = voxelsOf(rebuiltPts, 0.05);
	ASSERT_EQ(own.size(), ownPts.size());  // distinct voxels
	ASSERT_EQ(re.size(), rebuiltPts.size());
	EXPECT_GT(own.size(), 1000u);
	EXPECT_NEAR(static_cast<double>(re.size()) / own.size(), 1.0, 0.1);
	std::size_t common = 0;
	for (const auto& v : re) common += own.count(v);
	const double jaccard = static_cast<double>(common) / (own.size() + re.size() - common);
	EXPECT_GT(jaccard, 0.85);
}

TEST(Outputs, MapOutputsShareTheEstimatedFloorFrame)
{
	// One T_world_floor (z up, z = 0 on the floor) for every output. The sim world
	// is z up with the floor at z = 0 and the SLAM world is the first camera's frame, so the
	// true floor in the SLAM world is inverse(T_sim_cam0) of the sim's z = 0.
	const std::string out = runSlamOnShortSimSequence();
	ASSERT_FALSE(out.empty());
	const std::string report = test::readTextFile(out + "/report.json");
	EXPECT_EQ(nlohmann::json::parse(report)["floor"]["source"], "estimated");
	const auto T_world_floor = reportFloorPose(report);
	ASSERT_TRUE(T_world_floor);
	const auto gt = core::readTumTrajectory(mrpt::system::extractFileDirectory(out) + "/seq/groundtruth.txt");
	ASSERT_FALSE(gt.empty());
	const mrpt::poses::CPose3D T_sim_floor = gt.front().T_world_cam + *T_world_floor;
	EXPECT_NEAR(T_sim_floor.z(), 0.0, 0.02);
	EXPECT_GT(T_sim_floor.getRotationMatrix()(2, 2), std::cos(1.0 * M_PI / 180.0));

	// Every map file records the same frame.
	const std::string comment = maps::floorFrameComment(*T_world_floor);
	EXPECT_NE(test::readTextFile(out + "/map_3d.ply").find("comment " + comment + "\n"), std::string::npos);
	EXPECT_NE(test::readTextFile(out + "/hoc_points.ply").find("comment " + comment + "\n"), std::string::npos);
	EXPECT_EQ(test::readTextFile(out + "/map_2d.yaml").rfind("# " + comment + "\n", 0), 0u);
	{
		std::ifstream bt(out + "/map_3d.bt");
		std::string first, second;
		std::getline(bt, first);
		std::getline(bt, second);
		EXPECT_EQ(second, "# " + comment);
		octomap::OcTree tree(0.1);
		EXPECT_TRUE(tree.readBinary(out + "/map_3d.bt"));
		EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
	}

	// map_3d.ply: the floor's voxels are the lowest, at z ~ 0 (one 5 cm voxel), the walls
	// reach up to the 2.5 m ceiling; z is up.
	const auto ply = plyPoints(out + "/map_3d.ply");
	ASSERT_GT(ply.size(), 1000u);
	std::vector<double> z;
	for (const auto& p : ply) z.push_back(p.z);
	EXPECT_NEAR(quantile(z, 0.005), 0.0, 0.05);
	EXPECT_GT(quantile(z, 0.99), 1.5);
	EXPECT_LT(quantile(z, 1.0), 2.6);

	// hoc_points.ply: the landmarks of hoc_points.bin (SLAM world) moved into the floor frame.
	keygrid::CHOCPointsMap hoc;
	loadGz(out + "/hoc_points.bin", hoc);
	const auto hocPly = plyPoints(out + "/hoc_points.ply");
	ASSERT_EQ(hocPly.size(), hoc.size());
	ASSERT_GT(hocPly.size(), 100u);
	double worst = 0;
	std::vector<double> hz;
	for (std::size_t i = 0; i < hocPly.size(); i++)
	{
		worst = std::max(worst, (T_world_floor->composePoint(hocPly[i]) - hoc.points()[i].p).norm());
		hz.push_back(hocPly[i].z);
	}
	EXPECT_LT(worst, 1e-4);
	EXPECT_GT(quantile(hz, 0.01), -0.05);

	// trajectory_floor.txt: T_floor_cam of every frame; the sim camera flies at 1.3 m.
	const auto traj = core::readTumTrajectory(out + "/trajectory.txt");
	const auto trajFloor = core::readTumTrajectory(out + "/trajectory_floor.txt");
	ASSERT_EQ(traj.size(), trajFloor.size());
	for (std::size_t i = 0; i < traj.size(); i++)
	{
		const mrpt::poses::CPose3D expected = -*T_world_floor + traj[i].T_world_cam;
		EXPECT_LT((trajFloor[i].T_world_cam.translation() - expected.translation()).norm(), 1e-4);
		EXPECT_NEAR(trajFloor[i].T_world_cam.z(), 1.3, 0.03);
	}
}

TEST(Outputs, FloorFrameExistsWithOnlyThe3DGrid)
{
	// The floor estimate belongs to the run, not to the 2D grid: with the 3D grid alone, its
	// files are in the floor frame all the same.
	const std::string dir = test::scratchDir("outputs_floor_3d_only");
	auto run = test::renderAndRunSlam(
		dir, "--scene " + test::dataDir() + "/sim/room_arc.ini --frames 40 --voxel-resolution 0 --floorplan-resolution 0", false);
	ASSERT_TRUE(run.rendered) << run.simLog;
	auto o = run.options;
	o.output = dir + "/out3d";
	o.set = "MappingApplication.ismOccupancyGrid2D_count = 0; MappingApplication.hocPointsMap_count = 0";
	const auto r = slam::runSlam(o);
	ASSERT_TRUE(r.error.empty()) << r.error;
	EXPECT_FALSE(mrpt::system::fileExists(o.output + "/map_2d.yaml"));
	const auto T_world_floor = reportFloorPose(test::readTextFile(o.output + "/report.json"));
	ASSERT_TRUE(T_world_floor);
	const auto gt = core::readTumTrajectory(dir + "/seq/groundtruth.txt");
	const mrpt::poses::CPose3D T_sim_floor = gt.front().T_world_cam + *T_world_floor;
	EXPECT_NEAR(T_sim_floor.z(), 0.0, 0.02);
	EXPECT_GT(T_sim_floor.getRotationMatrix()(2, 2), std::cos(1.0 * M_PI / 180.0));
	EXPECT_NE(test::readTextFile(o.output + "/map_3d.ply").find("comment " + maps::floorFrameComment(*T_world_floor)), std::string::npos);
	std::vector<double> z;
	for (const auto& p : plyPoints(o.output + "/map_3d.ply")) z.push_back(p.z);
	ASSERT_GT(z.size(), 1000u);
	EXPECT_NEAR(quantile(z, 0.005), 0.0, 0.05);
}

TEST(Outputs, RawlogEditLoadsTheMapsPlugin)
{
	KEYGRID_SKIP_IF_SANITIZED();
	// A rawlog holding a keygrid map between two MRPT observations: rawlog-edit can read past
	// the map only when the plugin registered its class.
	const std::string dir = test::scratchDir("slam_outputs_rawlog_edit");
	const std::string rawlog = dir + "/with_map.rawlog";
	{
		mrpt::io::CFileGZOutputStream f(rawlog);
		auto a = mrpt::serialization::archiveFrom(f);
		auto c = mrpt::obs::CObservationComment::Create();
		c->text = "before the map";
		a << *c;
		CSubmappedOccupancyGrid3D grid(0.1);
		a << grid;
		c->text = "after the map";
		a << *c;
	}
	std::string log;
	ASSERT_EQ(test::runCommand("rawlog-edit -p " KEYGRID_MAPS_LIBRARY " --info -i " + rawlog, &log), 0) << log;
	EXPECT_EQ(log.find("not registered"), std::string::npos) << log;
	EXPECT_TRUE(std::regex_search(log, std::regex("Overall number of objects *: 3\\n"))) << log;
	// Control: without the plugin the same file stops at the map.
	ASSERT_EQ(test::runCommand("rawlog-edit --info -i " + rawlog, &log), 0) << log;
	EXPECT_NE(log.find("'keygrid::CSubmappedOccupancyGrid3D' which is not registered"), std::string::npos) << log;
}

// keygrid-sim outputs: same seed -> same bytes; the rawlog, TUM folder and ground truth are
// readable by keygrid's frame sources, rawlog-edit and the TUM trajectory reader.
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/TumFrameSource.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/SequenceWriter.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/imgcodecs.hpp>

#include <opencv2/core.hpp>

#include "SimTestScenes.h"
#include "TestData.h"

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace keygrid;

namespace
{
/** A tiny room with a moving cylinder: 4 frames of 160 x 120, noise on. */
std::string tinyRoomIni(int seed)
{
	return "[scene]\nname = tiny\nseed = " + std::to_string(seed) + "\nframes = 4\n" +
		   test::tinyCameraIni() +
		   "[trajectory]\nloop = true\nwp_00 = 1 1 1.2  3 1 1\nwp_01 = 1.2 1.2 1.2  1.2 3 1\n"
		   "[output]\nvoxel_resolution = 0.1\nfloorplan_resolution = 0.1\nwrite_mask = true\n"
		   "[object.floor]\ntype = quad\ncorner = 0 0 0\nedge1 = 3 0 0\nedge2 = 0 3 0\n"
		   "[object.wall_e]\ntype = quad\ncorner = 3 0 0\nedge1 = 0 3 0\nedge2 = 0 0 2.5\n"
		   "[object.wall_n]\ntype = quad\ncorner = 0 3 0\nedge1 = 3 0 0\nedge2 = 0 0 2.5\n"
		   "[object.box]\ntype = box\ncentre = 2.5 1.5 0.4\nsize = 0.5 0.5 0.8\nyaw = 15\n"
		   "[object.person]\ntype = cylinder\ncentre = 2.2 0.5 0.9\nradius = 0.2\nheight = 1.8\n"
		   "dynamic = true\npath_00 = 0 2.2 0.5 0.9\npath_01 = 1 2.2 2.5 0.9\n";
}

std::string writeScene(const std::string& name, const std::string& ini)
{
	const std::string dir = test::scratchDir(name);
	std::ofstream(dir + "/scene.ini") << ini;
	return dir + "/scene.ini";
}

std::string slurp(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

/** Relative paths of all regular files under dir, sorted. */
std::vector<std::string> listFiles(const std::string& dir)
{
	std::vector<std::string> out;
	for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
		if (e.is_regular_file()) out.push_back(std::filesystem::relative(e.path(), dir).string());
	std::sort(out.begin(), out.end());
	return out;
}
}  // namespace

TEST(SequenceOutputs, SameSeedGivesByteIdenticalFiles)
{
	const sim::Scene scene = test::sceneFromString(tinyRoomIni(3));
	sim::OutputOptions o;
	o.writeMask = true;
	const std::string a = test::scratchDir("sim_det_a"), b = test::scratchDir("sim_det_b");
	sim::writeSequence(scene, a, o, {}, 2);
	sim::writeSequence(scene, b, o, {}, 1);  // thread count must not matter either
	const auto files = listFiles(a);
	ASSERT_EQ(files, listFiles(b));
	EXPECT_GE(files.size(), 4u * 3 + 9);  // rgb, depth, mask per frame + lists, rawlog, gt...
	for (const auto& f : files) EXPECT_EQ(slurp(a + "/" + f), slurp(b + "/" + f)) << f;

	// Another seed changes textures and noise, not the ground truth.
	const std::string c = test::scratchDir("sim_det_c");
	sim::writeSequence(test::sceneFromString(tinyRoomIni(4)), c, o, {}, 2);
	EXPECT_NE(slurp(a + "/sequence.rawlog"), slurp(c + "/sequence.rawlog"));
	EXPECT_EQ(slurp(a + "/groundtruth.txt"), slurp(c + "/groundtruth.txt"));
}

TEST(SequenceOutputs, ToolNeverWritesIntoTheSceneFile)
{
	// Regression: overriding the seed once rewrote the user's scene INI.
	const std::string scene = writeScene("sim_tool_ro", tinyRoomIni(2));
	const std::string before = slurp(scene);
	std::string log;
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-sim") + " --quiet --seed 99 --frames 2 --scene " + scene +
								   " --output " + test::scratchDir("sim_tool_ro_out"), &log), 0)
		<< log;
	EXPECT_EQ(slurp(scene), before);
}

TEST(SequenceOutputs, SetOverridesSceneKeysLikeTheFileWould)
{
	// --set section.key=value gives the same bytes as the key written into the scene file, and
	// a misspelt key is an error naming it (MRPT would ignore it silently).
	const std::string plain = writeScene("sim_set_plain", tinyRoomIni(5));
	const std::string edited = writeScene(
		"sim_set_edited", tinyRoomIni(5) + "[sensor]\ndisparity_distortion = 0.5\n");
	const std::string tool = test::toolPath("keygrid-sim") + " --quiet --frames 2 ";
	const std::string a = test::scratchDir("sim_set_a"), b = test::scratchDir("sim_set_b"),
					  c = test::scratchDir("sim_set_c");
	std::string log;
	ASSERT_EQ(test::runCommand(tool + "--set 'sensor.disparity_distortion=0.5' --scene " + plain + " --output " + a, &log), 0) << log;
	ASSERT_EQ(test::runCommand(tool + "--scene " + edited + " --output " + b, &log), 0) << log;
	ASSERT_EQ(test::runCommand(tool + "--scene " + plain + " --output " + c, &log), 0) << log;
	const std::vector<std::string> depth = listFiles(a + "/tum/depth");
	ASSERT_EQ(depth.size(), 2u);
	for (const std::string& f : depth)
	{
		EXPECT_EQ(slurp(a + "/tum/depth/" + f), slurp(b + "/tum/depth/" + f)) << f;
		EXPECT_NE(slurp(a + "/tum/depth/" + f), slurp(c + "/tum/depth/" + f)) << f;
	}
	EXPECT_NE(test::runCommand(tool + "--set 'sensor.disparity_distorsion=0.5' --scene " + plain + " --output " + a, &log), 0);
	EXPECT_NE(log.find("disparity_distorsion"), std::string::npos) << log;
	EXPECT_NE(test::runCommand(tool + "--set 'sensor.noise' --scene " + plain + " --output " + a, &log), 0);
	EXPECT_NE(log.find("--set"), std::string::npos) << log;
}

TEST(SequenceOutputs, ToolOutputsAreReadable)
{
	const std::string scene = writeScene("sim_tool_in", tinyRoomIni(9));
	const std::string out = test::scratchDir("sim_tool_out");
	std::string log;
	ASSERT_EQ(
		test::runCommand(
			test::toolPath("keygrid-sim") + " --quiet --scene " + scene + " --output " + out, &log),
		0)
		<< log;
	EXPECT_NE(log.find("wrote 4 frames"), std::string::npos) << log;

	// groundtruth.txt: one pose per frame, at the frame timestamps.
	const core::Trajectory gt = core::readTumTrajectory(out + "/groundtruth.txt");
	ASSERT_EQ(gt.size(), 4u);
	EXPECT_NEAR(gt[1].t - gt[0].t, 1.0 / 30, 1e-6);

	// The rawlog through keygrid's own reader: same depth integers as the TUM PNGs.
	core::RawlogFrameSource src(out + "/sequence.rawlog");
	core::TumFrameSource tum(out + "/tum");
	EXPECT_EQ(tum.sequence().pairs().size(), 4u);
	EXPECT_EQ(tum.sequence().guessCamera().fx, 131.25);
	core::Frame fr, ft;
	std::size_t n = 0;
	while (src.next(fr))
	{
		ASSERT_TRUE(tum.next(ft));
		EXPECT_NEAR(fr.timestamp, gt[n].t, 1e-6);
		EXPECT_EQ(fr.camera.width, 160u);
		EXPECT_FLOAT_EQ(fr.camera.depthUnits, 0.0002f);
		EXPECT_EQ(cv::norm(fr.depthRaw, ft.depthRaw, cv::NORM_INF), 0.0);
		EXPECT_EQ(cv::norm(fr.colour, ft.colour, cv::NORM_INF), 0.0);
		EXPECT_GT(cv::countNonZero(fr.depthRaw), 160 * 120 / 2);
		n++;
	}
	EXPECT_EQ(n, 4u);

	// MRPT's own tool reads it.
	std::string info;
	ASSERT_EQ(test::runCommand("rawlog-edit --info -i " + out + "/sequence.rawlog", &info), 0)
		<< info;
	EXPECT_NE(info.find("Overall number of objects         : 4"), std::string::npos) << info;

	// Ground-truth occupancy and the mask folder.
	EXPECT_GT(sim::VoxelSet::load(out + "/occupancy_voxels.txt").size(), 100u);
	EXPECT_GT(sim::FloorPlan::load(out + "/floorplan.yaml").occupiedCount(), 10u);
	EXPECT_EQ(listFiles(out + "/tum/mask").size(), 4u);
	const cv::Mat mask =
		cv::imread(out + "/tum/mask/" + listFiles(out + "/tum/mask")[0], cv::IMREAD_UNCHANGED);
	EXPECT_EQ(mask.type(), CV_8UC1);

	// Augment mode through the tool: the objects of a trajectory-less scene into this output.
	const std::string objects = writeScene(
		"sim_tool_aug_in",
		"[scene]\nseed = 9\n[object.ball]\ntype = cylinder\ncentre = 2.2 1.1 0.9\nradius = 0.3\n"
		"height = 0.6\ndynamic = true\n");
	const std::string aug = test::scratchDir("sim_tool_aug_out");
	ASSERT_EQ(
		test::runCommand(
			test::toolPath("keygrid-sim") + " --quiet --augment " + out + "/tum --scene " +
				objects + " --output " + aug,
			&log),
		0)
		<< log;
	EXPECT_NE(log.find("wrote 4 augmented frames"), std::string::npos) << log;
	EXPECT_EQ(core::readTumTrajectory(aug + "/groundtruth.txt").size(), 4u);
	EXPECT_EQ(listFiles(aug + "/tum/mask").size(), 4u);

	// Bad input: a one-line reason and a non-zero exit code.
	ASSERT_NE(
		test::runCommand(
			test::toolPath("keygrid-sim") + " --scene /nonexistent.ini --output " + out, &log),
		0);
	EXPECT_NE(log.find("does not exist"), std::string::npos) << log;
}

TEST(SequenceOutputs, AStoppedRunWritesTheFramesSoFarAsAWholeSequence)
{
	const sim::Scene scene = test::sceneFromString(tinyRoomIni(5));
	sim::OutputOptions o;
	const std::string dir = test::scratchDir("sim_stopped");
	std::size_t asked = 0;
	// Stop before the third frame (Ctrl-C in keygrid-sim).
	const auto s = sim::writeSequence(scene, dir, o, {}, 1, [&] { return ++asked > 2; });
	EXPECT_TRUE(s.stopped);
	EXPECT_EQ(s.frames, 2u);
	EXPECT_EQ(core::readTumTrajectory(dir + "/groundtruth.txt").size(), 2u);
	core::TumFrameSource tum(dir + "/tum");
	core::Frame f;
	std::size_t n = 0;
	while (tum.next(f)) n++;
	EXPECT_EQ(n, 2u);
	for (const auto& file : listFiles(dir)) EXPECT_EQ(file.find(".tmp"), std::string::npos) << file;
}

TEST(SequenceOutputs, AWriteErrorLeavesNoListOrRawlogUnderItsFinalName)
{
	const sim::Scene scene = test::sceneFromString(tinyRoomIni(5));
	sim::OutputOptions o;
	o.voxelResolution = 0;
	o.floorPlanResolution = 0;
	const std::string dir = test::scratchDir("sim_write_error");
	std::filesystem::remove_all(dir);
	// The second frame's colour image cannot be written: a folder holds its name.
	char ts[32];
	std::snprintf(ts, sizeof(ts), "%.6f", scene.timestamp(1));
	std::filesystem::create_directories(dir + "/tum/rgb/" + ts + ".png");
	EXPECT_THROW(sim::writeSequence(scene, dir, o, {}, 1), std::runtime_error);
	for (const char* f : {"sequence.rawlog", "groundtruth.txt", "tum/rgb.txt", "tum/depth.txt", "tum/associations.txt"})
		EXPECT_FALSE(std::filesystem::exists(dir + "/" + f)) << f;
	for (const auto& file : listFiles(dir)) EXPECT_EQ(file.find(".tmp"), std::string::npos) << file;
}

TEST(SequenceOutputs, MonocularSequenceHasTheRgbdImagesWithoutDepth)
{
	const sim::Scene scene = test::sceneFromString(tinyRoomIni(6));
	sim::OutputOptions o;
	o.voxelResolution = o.floorPlanResolution = 0;
	const std::string rgbd = test::scratchDir("sim_mono_rgbd"), mono = test::scratchDir("sim_mono");
	sim::writeSequence(scene, rgbd, o, {}, 2);
	o.sensor = sim::RecordedSensor::Monocular;
	sim::writeSequence(scene, mono, o, {}, 2);

	// The TUM folder has the colour images and rgb.txt alone; images and ground truth are the
	// RGB-D sequence's, byte for byte.
	const auto files = listFiles(mono);
	for (const auto& f : files)
		EXPECT_EQ(f.find("depth"), std::string::npos) << f;
	EXPECT_FALSE(std::filesystem::exists(mono + "/tum/associations.txt"));
	EXPECT_EQ(listFiles(mono + "/tum/rgb"), listFiles(rgbd + "/tum/rgb"));
	for (const auto& f : listFiles(mono + "/tum/rgb"))
		EXPECT_EQ(slurp(mono + "/tum/rgb/" + f), slurp(rgbd + "/tum/rgb/" + f)) << f;
	for (const char* f : {"groundtruth.txt", "tum/groundtruth.txt", "tum/rgb.txt", "tum/camera.ini"})
		EXPECT_EQ(slurp(mono + "/" + f), slurp(rgbd + "/" + f)) << f;

	// The rawlog holds CObservationImage: image-only frames equal to the RGB-D rawlog's images,
	// in the same camera; RGB-D mode skips them, and the TUM folder refuses to give depth.
	core::FrameSourceOptions imagesOnly;
	imagesOnly.depth = core::DepthUse::Ignore;
	core::RawlogFrameSource a(rgbd + "/sequence.rawlog"), b(mono + "/sequence.rawlog", imagesOnly);
	core::TumFrameSource t(mono + "/tum", imagesOnly);
	core::Frame fa, fb, ft;
	std::size_t n = 0;
	while (a.next(fa))
	{
		ASSERT_TRUE(b.next(fb)) << b.lastSkipReason();
		ASSERT_TRUE(t.next(ft));
		EXPECT_FALSE(fb.hasDepth());
		EXPECT_FALSE(ft.hasDepth());
		EXPECT_EQ(cv::norm(fa.colour, fb.colour, cv::NORM_INF), 0.0);
		EXPECT_EQ(cv::norm(fa.grey, fb.grey, cv::NORM_INF), 0.0);
		EXPECT_EQ(cv::norm(fb.colour, ft.colour, cv::NORM_INF), 0.0);
		EXPECT_EQ(fa.timestamp, fb.timestamp);
		EXPECT_NEAR(fb.timestamp, ft.timestamp, 1e-6);
		EXPECT_EQ(fb.camera.fx, fa.camera.fx);
		EXPECT_EQ(fb.camera.width, 160u);
		n++;
	}
	EXPECT_EQ(n, 4u);
	EXPECT_FALSE(b.next(fb));
	core::RawlogFrameSource asRgbd(mono + "/sequence.rawlog");
	EXPECT_FALSE(asRgbd.next(fa));
	EXPECT_EQ(asRgbd.skippedCount(), 4u);
	try
	{
		core::TumFrameSource withDepth(mono + "/tum");
		FAIL();
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find(mono + "/tum' has neither associations.txt nor depth.txt"), std::string::npos)
			<< e.what();
	}
}

TEST(SequenceOutputs, OutputSensorKeyIsReadSavedAndChecked)
{
	mrpt::config::CConfigFileMemory cfg;
	sim::OutputOptions o;
	o.sensor = sim::RecordedSensor::Monocular;
	o.saveToConfigFile(cfg, "output");
	EXPECT_EQ(cfg.read_string("output", "sensor", ""), "monocular");
	sim::OutputOptions back;
	back.loadFromConfigFile(cfg, "output");
	EXPECT_EQ(back.sensor, sim::RecordedSensor::Monocular);
	cfg.write("output", "sensor", "rgbd");
	back.loadFromConfigFile(cfg, "output");
	EXPECT_EQ(back.sensor, sim::RecordedSensor::Rgbd);
	cfg.write("output", "sensor", "stereo");
	try
	{
		back.loadFromConfigFile(cfg, "output");
		FAIL();
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[output] sensor = 'stereo'"), std::string::npos) << e.what();
	}
}

TEST(SequenceOutputs, BenchmarkSceneRendersAsMonocularThroughTheTool)
{
	// keygrid-sim --set 'output.sensor=monocular' on the shipped room_loop scene (camera at a
	// fixed height): a monocular sequence the image-only sources read.
	const std::string out = test::scratchDir("sim_tool_mono");
	std::string log;
	ASSERT_EQ(
		test::runCommand(
			test::toolPath("keygrid-sim") + " --quiet --frames 2 --voxel-resolution 0 --floorplan-resolution 0 " +
				"--set 'output.sensor=monocular' --scene " + test::sourceDir() + "/config/sim/room_loop.ini --output " + out,
			&log),
		0)
		<< log;
	EXPECT_FALSE(std::filesystem::exists(out + "/tum/depth"));
	EXPECT_FALSE(std::filesystem::exists(out + "/tum/depth.txt"));
	core::FrameSourceOptions imagesOnly;
	imagesOnly.depth = core::DepthUse::Ignore;
	for (const std::string& input : {out + "/sequence.rawlog", out + "/tum"})
	{
		auto src = core::openFrameSource(input, imagesOnly);
		core::Frame f;
		std::size_t n = 0;
		while (src->next(f))
		{
			EXPECT_FALSE(f.hasDepth()) << input;
			EXPECT_EQ(f.grey.size(), cv::Size(640, 480)) << input;
			n++;
		}
		EXPECT_EQ(n, 2u) << input;
		EXPECT_EQ(src->skippedCount(), 0u) << input << ": " << src->lastSkipReason();
	}
	// Camera height above the floor (z = 0): the scene's, for every frame.
	for (const auto& p : core::readTumTrajectory(out + "/groundtruth.txt")) EXPECT_NEAR(p.T_world_cam.z(), 1.30, 1e-4);
}

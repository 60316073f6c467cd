// keygrid-slam --live and run interruption: the live configurations load (keygrid's and
// rawlog-grabber's, checked by MRPT's own COpenNI2Sensor::loadConfig), the newest-frame-only
// source drops what a slow consumer cannot take, a run without a device fails with one clear
// line, and Ctrl-C / SIGTERM stop a run that still writes its outputs.
#include <keygrid/core/FrameConventions.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/LiveFrameSource.h>
#include <keygrid/slam/LiveRun.h>
#include <keygrid/slam/LivePreview.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/OpenNI2FrameSource.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/System.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/hwdrivers/COpenNI2Sensor.h>
#include <mrpt/system/filesystem.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fcntl.h>
#include <thread>

#include "SlamRunHelpers.h"
#include "TestData.h"

using namespace keygrid;

namespace
{
/** A source of `n` helper frames, each after `period` of "exposure"; optionally throws after
 * `failAfter` frames. */
class PacedSource : public core::FrameSource
{
   public:
	PacedSource(std::size_t n, std::chrono::microseconds period, std::size_t failAfter = 0)
		: m_n(n), m_period(period), m_failAfter(failAfter)
	{
	}
	bool next(core::Frame& out) override
	{
		if (m_failAfter && m_i == m_failAfter) throw std::runtime_error("camera unplugged");
		if (m_i >= m_n) return false;
		std::this_thread::sleep_for(m_period);
		out = test::texturedFrame(m_i);
		out.index = m_i++;
		return true;
	}
	std::optional<std::size_t> sizeHint() const override { return m_n; }
	std::string describe() const override { return "paced test source"; }

   private:
	std::size_t m_n, m_i{0};
	std::chrono::microseconds m_period;
	std::size_t m_failAfter;
};

// MRPT 2.5's ~COpenNI2Sensor() throws when no device is connected (std::terminate): sensors
// made on a machine without one are kept alive until exit instead.
mrpt::hwdrivers::COpenNI2Sensor& undestroyedSensor()
{
	static auto* sensors = new std::vector<std::unique_ptr<mrpt::hwdrivers::COpenNI2Sensor>>();
	sensors->push_back(std::make_unique<mrpt::hwdrivers::COpenNI2Sensor>());
	return *sensors->back();
}
}  // namespace

TEST(LiveFrameSource, SlowConsumerGetsTheNewestFrameAndTheRestAreCountedAsDropped)
{
	// The consumer looks only once the camera finished: it must get the last frame, and every
	// earlier one was replaced before it was taken.
	slam::LiveFrameSource live(std::make_unique<PacedSource>(50, std::chrono::microseconds(0)));
	while (live.grabbedCount() < 50) std::this_thread::sleep_for(std::chrono::milliseconds(1));
	core::Frame f;
	ASSERT_TRUE(live.next(f));
	EXPECT_EQ(f.index, 49u);
	EXPECT_FALSE(live.next(f));
	EXPECT_EQ(live.droppedCount(), 49u);
}

TEST(LiveFrameSource, EveryFrameIsEitherDeliveredInOrderOrCountedAsDropped)
{
	slam::LiveFrameSource live(std::make_unique<PacedSource>(40, std::chrono::microseconds(500)));
	core::Frame f;
	std::vector<std::size_t> got;
	while (live.next(f))
	{
		got.push_back(f.index);
		std::this_thread::sleep_for(std::chrono::milliseconds(got.size() % 3 ? 0 : 3));  // uneven consumer
	}
	ASSERT_FALSE(got.empty());
	for (std::size_t i = 1; i < got.size(); i++) EXPECT_LT(got[i - 1], got[i]);
	EXPECT_EQ(got.back(), 39u);  // the newest frame is never lost
	EXPECT_EQ(live.grabbedCount(), 40u);
	EXPECT_EQ(got.size() + live.droppedCount(), 40u);
}

TEST(LiveFrameSource, CameraErrorsComeAfterTheFramesBeforeThemAndStopWhenEndsTheWait)
{
	slam::LiveFrameSource failing(std::make_unique<PacedSource>(10, std::chrono::microseconds(0), 3));
	while (failing.grabbedCount() < 3) std::this_thread::sleep_for(std::chrono::milliseconds(1));
	std::this_thread::sleep_for(std::chrono::milliseconds(20));
	core::Frame f;
	ASSERT_TRUE(failing.next(f));
	EXPECT_EQ(f.index, 2u);
	try
	{
		failing.next(f);
		ADD_FAILURE() << "no exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_STREQ(e.what(), "camera unplugged");
	}

	// A camera that never delivers: stopWhen (the interrupt flag in keygrid-slam) ends next().
	std::atomic<bool> stop{false};
	slam::LiveFrameSourceOptions o;
	o.stopWhen = [&] { return stop.load(); };
	slam::LiveFrameSource idle(std::make_unique<PacedSource>(1, std::chrono::milliseconds(400)), o);
	std::thread t([&] {
		std::this_thread::sleep_for(std::chrono::milliseconds(50));
		stop = true;
	});
	EXPECT_FALSE(idle.next(f));
	t.join();
}

TEST(LiveCapture, LiveLoopTracksTheNewestFramesAndCountsTheRest)
{
	const std::string dir = test::scratchDir("live_loop");
	const slam::SlamConfig cfg = slam::SlamConfig::FromFile(test::writeFastConfig(dir + "/fast.ini"));
	{
		slam::System sys(cfg);
		slam::LiveFrameSource src(std::make_unique<PacedSource>(30, std::chrono::milliseconds(1)));
		std::size_t calls = 0;
		const auto r = slam::runLiveLoop(sys, src, {}, [&](const sfm::TrackedFrame&) { calls++; });
		EXPECT_EQ(r.grabbed, 30u);
		EXPECT_EQ(calls + r.dropped, 30u);
		EXPECT_EQ(sys.stats().frames, calls);
		ASSERT_FALSE(sys.frames().empty());
		EXPECT_EQ(sys.frames().back().timestamp, test::texturedFrame(29).timestamp);  // the newest is never dropped
		EXPECT_GT(sys.stats().tracked, 0u);
	}
	{
		slam::System sys(cfg);
		slam::LiveFrameSource src(std::make_unique<PacedSource>(30, std::chrono::milliseconds(1)));
		slam::LiveLoopOptions o;
		o.maxFrames = 5;
		const auto r = slam::runLiveLoop(sys, src, o, [](const sfm::TrackedFrame&) {});
		EXPECT_EQ(sys.stats().frames, 5u);
		EXPECT_LE(r.grabbed, 30u);
	}
	{
		// Interrupted before the first frame: the loop ends at once, cleanly.
		slam::System sys(cfg);
		slam::LiveFrameSource src(std::make_unique<PacedSource>(30, std::chrono::milliseconds(1)));
		slam::requestInterrupt();
		const auto r = slam::runLiveLoop(sys, src, {}, [](const sfm::TrackedFrame&) {});
		slam::clearInterrupt();
		EXPECT_EQ(sys.stats().frames, 0u);
		EXPECT_LE(r.grabbed, 30u);
	}
}

TEST(LiveCapture, PreviewDrawsKeypointsAndTrackedPoints)
{
	const core::Frame f = test::texturedFrame(0);
	std::vector<cv::KeyPoint> kps{cv::KeyPoint(40.f, 80.f, 7.f)};
	sfm::TrackedFrame tf;
	tf.tracked = true;
	sfm::FrameObservation ob;
	ob.u = 120.f;
	ob.v = 90.f;
	tf.observations.push_back(ob);
	const cv::Mat img = slam::LivePreview::render(f, kps, tf, "status");
	ASSERT_EQ(img.type(), CV_8UC3);
	ASSERT_EQ(img.size(), f.grey.size());
	// Keypoint ring in yellow (B=0, G=220, R=255) 2 px from its centre; tracked point in green.
	EXPECT_EQ(img.at<cv::Vec3b>(80, 42), cv::Vec3b(0, 220, 255));
	EXPECT_EQ(img.at<cv::Vec3b>(90, 123), cv::Vec3b(0, 255, 0));
	// Untouched pixels keep the grey image.
	const uint8_t g = f.grey.at<uint8_t>(60, 10);
	EXPECT_EQ(img.at<cv::Vec3b>(60, 10), cv::Vec3b(g, g, g));
}

TEST(LiveCapture, PreviewWindowOpensWhenADisplayExists)
{
	if (!slam::LivePreview::displayAvailable()) GTEST_SKIP() << "no $DISPLAY (run under xvfb-run to test the window)";
	slam::LivePreview preview("keygrid test preview");
	EXPECT_FALSE(preview.closed());
	sfm::TrackedFrame tf;
	for (std::size_t i = 0; i < 3; i++) preview.show(test::texturedFrame(i), {}, tf, "frame " + std::to_string(i));
	EXPECT_FALSE(preview.closed());
}

TEST(LiveCapture, ShippedLiveConfigLoads)
{
	const std::string path = test::sourceDir() + "/config/kinect_openni2.ini";
	const slam::SlamConfig cfg = slam::SlamConfig::FromFile(path);
	EXPECT_EQ(cfg.mode, slam::RunMode::Threaded);
	EXPECT_EQ(cfg.camera, "kinect");
	mrpt::config::CConfigFile ini(path);
	const slam::MetricMaps maps(ini, cfg.maps);
	EXPECT_EQ(maps.size(), 2u);
	slam::OpenNI2SourceOptions so;
	so.loadFromConfigFile(ini, "live");
	EXPECT_EQ(so.frameTimeout, 5.0);
	EXPECT_TRUE(so.depthRegistered);
	// The [live] section is what MRPT's driver reads, and it accepts it.
	auto& sensor = undestroyedSensor();
	ASSERT_NO_THROW(sensor.loadConfig(ini, "live"));
	EXPECT_EQ(sensor.getSensorLabel(), "KINECT");
	EXPECT_FALSE(sensor.isGrab3DPointsEnabled());
	// Its calibration sections say "registered": one camera model, the standard axis change.
	EXPECT_TRUE(sensor.getCameraParamsIntensity() == sensor.getCameraParamsDepth());
	EXPECT_LT(sensor.getRelativePoseIntensityWrtDepth().distanceTo(core::T_depth_cam()), 1e-9);
	EXPECT_EQ(sensor.getCameraParamsIntensity().fx(), core::RgbdCamera::Preset("kinect").fx);
	// The Kinect preset matches the configured stream size.
	const auto cam = core::RgbdCamera::Preset(cfg.camera);
	EXPECT_EQ(cam.width, static_cast<unsigned>(ini.read_int("live", "width", 0)));
	EXPECT_EQ(cam.height, static_cast<unsigned>(ini.read_int("live", "height", 0)));

	mrpt::config::CConfigFileMemory bad;
	bad.write("live", "frame_timeout", "-1");
	EXPECT_THROW(so.loadFromConfigFile(bad, "live"), std::invalid_argument);
}

TEST(LiveCapture, RawlogGrabberIniHasWhatCOpenNI2SensorReads)
{
	const std::string path = test::sourceDir() + "/config/rawlog-grabber/kinect_openni2.ini";
	ASSERT_TRUE(mrpt::system::fileExists(path));
	mrpt::config::CConfigFile ini(path);
	// rawlog-grabber's own keys.
	EXPECT_EQ(ini.read_string("global", "rawlog_prefix", ""), "./kinect");
	EXPECT_EQ(ini.read_int("global", "rawlog_GZ_compress_level", -1), 0);
	EXPECT_EQ(ini.read_int("global", "use_sensoryframes", -1), 0);
	// Exactly one sensor thread, driven by COpenNI2Sensor; calibration sections are ignored by
	// the grabber itself.
	std::vector<std::string> sections, sensors;
	ini.getAllSections(sections);
	for (const auto& s : sections)
		if (s != "global" && !ini.read_bool(s, "rawlog-grabber-ignore", false)) sensors.push_back(s);
	ASSERT_EQ(sensors.size(), 1u);
	EXPECT_EQ(ini.read_string(sensors[0], "driver", ""), "COpenNI2Sensor");
	EXPECT_GT(ini.read_double(sensors[0], "process_rate", 0), ini.read_double(sensors[0], "fps", 0));

	auto& sensor = undestroyedSensor();
	ASSERT_NO_THROW(sensor.loadConfig(ini, sensors[0]));
	EXPECT_EQ(sensor.getSensorLabel(), "KINECT");
	EXPECT_EQ(sensor.getProcessRate(), 90.0);
	EXPECT_FALSE(sensor.isGrab3DPointsEnabled());
	EXPECT_TRUE(sensor.isGrabDepthEnabled());
	EXPECT_TRUE(sensor.isGrabRGBEnabled());
	// Depth registered to colour: one calibration for both and the standard axis change, so
	// keygrid reads the recorded observations as registered (no second registration).
	const auto& K = sensor.getCameraParamsIntensity();
	EXPECT_EQ(K.ncols, 640u);
	EXPECT_EQ(K.nrows, 480u);
	EXPECT_EQ(K.fx(), 525.0);
	EXPECT_TRUE(K == sensor.getCameraParamsDepth());
	const auto d = sensor.getRelativePoseIntensityWrtDepth().distanceTo(core::T_depth_cam());
	EXPECT_LT(d, 1e-9);
	mrpt::obs::CObservation3DRangeScan obs;
	obs.relativePoseIntensityWRTDepth = sensor.getRelativePoseIntensityWrtDepth();
	EXPECT_TRUE(obs.doDepthAndIntensityCamerasCoincide());
}

TEST(LiveCapture, WithoutADeviceExitsWithOneClearLine)
{
	if (slam::OpenNI2FrameSource::connectedDevices() > 0) GTEST_SKIP() << "an OpenNI2 device is connected";
	const std::string dir = test::scratchDir("live_nodevice");
	const auto r = test::runTool(
		"keygrid-slam", "--live --no-preview --config " + test::sourceDir() + "/config/kinect_openni2.ini --output " + dir + "/out");
	EXPECT_FALSE(r.signaled()) << r.output;
	EXPECT_EQ(r.exitCode(), 1) << r.output;
	EXPECT_NE(r.output.find("keygrid-slam: error: no OpenNI2 device found (is the Kinect/Xtion plugged in"), std::string::npos) << r.output;
	std::size_t ours = 0;
	for (std::size_t p = r.output.find("keygrid-slam:"); p != std::string::npos; p = r.output.find("keygrid-slam:", p + 1)) ours++;
	EXPECT_EQ(ours, 1u) << r.output;

	const auto both = test::runTool("keygrid-slam", "--live --input x.rawlog --config c.ini --output " + dir + "/o");
	EXPECT_EQ(both.exitCode(), 2) << both.output;
	EXPECT_NE(both.output.find("--live and --input exclude each other"), std::string::npos) << both.output;
}

namespace
{
/** Starts keygrid-slam with stdout+stderr into `log`; returns its pid. */
pid_t spawnSlam(const std::vector<std::string>& args, const std::string& log)
{
	const pid_t pid = fork();
	if (pid == 0)
	{
		const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, STDOUT_FILENO);
		dup2(fd, STDERR_FILENO);
		std::vector<char*> argv;
		const std::string tool = test::toolPath("keygrid-slam");
		argv.push_back(const_cast<char*>(tool.c_str()));
		for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
		argv.push_back(nullptr);
		execv(tool.c_str(), argv.data());
		_exit(127);
	}
	return pid;
}

/** Waits until `log` contains `text` (or `seconds` passed). */
bool waitForText(const std::string& log, const std::string& text, double seconds)
{
	const auto t0 = std::chrono::steady_clock::now();
	while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < seconds)
	{
		if (test::readTextFile(log).find(text) != std::string::npos) return true;
		std::this_thread::sleep_for(std::chrono::milliseconds(20));
	}
	return false;
}

/** keygrid-sim's 90-frame 640x480 test sequence: several seconds of work for keygrid-slam,
 * so a run is surely still going when the test interrupts it. Generated once per test process. */
const std::size_t kLongFrames = 90;
std::string longRawlog()
{
	static const std::string path = [] {
		// One folder per test: ctest runs the tests of this file as parallel processes.
		const std::string dir = test::scratchDir(std::string("interrupt_input_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
		std::string out;
		const int rc = test::runCommand(
			test::toolPath("keygrid-sim") + " --quiet --scene " + test::dataDir() + "/sim/room_arc.ini --output " + dir, &out);
		if (rc != 0) throw std::runtime_error("keygrid-sim failed: " + out);
		return dir + "/sequence.rawlog";
	}();
	return path;
}
}  // namespace

TEST(Interrupt, SigintAndSigtermStopTheRunWhichStillWritesItsOutputs)
{
	const std::string dir = test::scratchDir("interrupt_run");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	for (const char* mode : {"sequential", "threaded"})
		for (int sig : {SIGINT, SIGTERM})
		{
			SCOPED_TRACE(std::string(mode) + " signal " + std::to_string(sig));
			const std::string out = dir + "/" + mode + std::to_string(sig);
			const std::string log = out + ".log";
			const pid_t pid = spawnSlam({"--config", cfg, "--input", longRawlog(), "--output", out, "--mode", mode}, log);
			ASSERT_GT(pid, 0);
			// The frame loop starts right after this line.
			ASSERT_TRUE(waitForText(log, " mode\n", 60)) << test::readTextFile(log);
			std::this_thread::sleep_for(std::chrono::milliseconds(300));
			kill(pid, sig);
			int st = 0;
			ASSERT_EQ(waitpid(pid, &st, 0), pid);
			ASSERT_FALSE(WIFSIGNALED(st)) << "signal " << WTERMSIG(st) << "\n" << test::readTextFile(log);
			EXPECT_EQ(WEXITSTATUS(st), 128 + sig) << test::readTextFile(log);
			const std::string report = test::readTextFile(out + "/report.json");
			EXPECT_NE(report.find("\"interrupted\": true"), std::string::npos) << report;
			const double frames = test::jsonNumber(report, "frames");
			EXPECT_GT(frames, 0) << report;
			EXPECT_LT(frames, kLongFrames) << report;
			const std::size_t lines = test::countPoseLines(out + "/trajectory.txt");
			EXPECT_EQ(lines, static_cast<std::size_t>(frames));
			EXPECT_TRUE(mrpt::system::fileExists(out + "/keyframes.txt"));
			EXPECT_NE(test::readTextFile(log).find("interrupted after"), std::string::npos);
		}
}

TEST(Interrupt, SecondSigintExitsAtOnce)
{
	const std::string dir = test::scratchDir("interrupt_twice");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const std::string log = dir + "/run.log";
	const pid_t pid = spawnSlam({"--config", cfg, "--input", longRawlog(), "--output", dir + "/out"}, log);
	ASSERT_GT(pid, 0);
	ASSERT_TRUE(waitForText(log, " mode\n", 60)) << test::readTextFile(log);
	kill(pid, SIGINT);
	ASSERT_TRUE(waitForText(log, "interrupt again to quit", 10)) << test::readTextFile(log);
	kill(pid, SIGINT);
	int st = 0;
	ASSERT_EQ(waitpid(pid, &st, 0), pid);
	ASSERT_FALSE(WIFSIGNALED(st)) << test::readTextFile(log);
	EXPECT_EQ(WEXITSTATUS(st), 130) << test::readTextFile(log);
}

TEST(Interrupt, ReportOfAnUninterruptedRunSaysSo)
{
	const std::string dir = test::scratchDir("interrupt_none");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> obs;
	for (std::size_t i = 0; i < 3; i++) obs.push_back(test::texturedObservation(i));
	test::writeRawlog(dir + "/s.rawlog", obs);
	const auto r = test::runTool("keygrid-slam", "--quiet --config " + cfg + " --input " + dir + "/s.rawlog --output " + dir + "/out");
	EXPECT_EQ(r.exitCode(), 0) << r.output;
	EXPECT_NE(test::readTextFile(dir + "/out/report.json").find("\"interrupted\": false"), std::string::npos);
}

#include <keygrid/core/BoundedQueue.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/LivePreview.h>
#include <keygrid/slam/LiveRun.h>
#include <keygrid/slam/OpenNI2FrameSource.h>
#include <keygrid/slam/System.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <thread>

namespace keygrid::slam
{
namespace
{
struct Extracted
{
	core::Frame frame;
	sfm::FrameFeatures features;
	double extractSeconds{0};
};
}  // namespace

std::unique_ptr<LiveFrameSource> openLiveCamera(
	const mrpt::config::CConfigFileBase& ini, const std::string& origin, const SlamConfig& cfg)
{
	if (!ini.sectionExists("live"))
		throw std::invalid_argument(origin + ": no [live] section (the OpenNI2 sensor settings; see config/kinect_openni2.ini)");
	OpenNI2SourceOptions so;
	so.loadFromConfigFile(ini, "live");
	if (!cfg.camera.empty() && cfg.camera != "auto") so.camera = core::RgbdCamera::FromPresetOrFile(cfg.camera);
	auto camera = std::make_unique<OpenNI2FrameSource>(ini, "live", so);
	LiveFrameSourceOptions lo;
	lo.stopWhen = [] { return interruptRequested(); };
	lo.cancelInner = [cam = camera.get()] { cam->cancel(); };
	return std::make_unique<LiveFrameSource>(std::move(camera), std::move(lo));
}

LiveLoopResult runLiveLoop(
	System& sys, LiveFrameSource& source, const LiveLoopOptions& opts,
	const std::function<void(const sfm::TrackedFrame&)>& onFrame)
{
	using Clock = std::chrono::steady_clock;
	LiveLoopResult res;
	std::optional<LivePreview> preview;
	if (opts.preview) preview.emplace("keygrid-slam live");

	// Capacity 1: one frame waits while the previous one is tracked; anything newer replaces
	// older frames inside the LiveFrameSource (counted as dropped).
	core::BoundedQueue<Extracted> queue(1);
	std::string producerError;
	std::thread producer([&] {
		try
		{
			for (std::size_t n = 0; !(opts.maxFrames && n >= opts.maxFrames) && !interruptRequested(); n++)
			{
				Extracted e;
				if (!source.next(e.frame)) break;
				const auto t0 = Clock::now();
				e.features = sys.extract(e.frame);
				e.extractSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
				if (!queue.push(std::move(e))) break;
			}
		}
		catch (const std::exception& ex)
		{
			producerError = ex.what();
		}
		queue.close();
	});
	// However the loop below ends (an exception included), the producer is stopped and joined.
	struct Joiner
	{
		LiveFrameSource& source;
		core::BoundedQueue<Extracted>& queue;
		std::thread& thread;
		~Joiner()
		{
			source.stop();
			queue.close();
			if (thread.joinable()) thread.join();
		}
	} joiner{source, queue, producer};
	while (auto e = queue.pop())
	{
		sys.timings().add("extract", e->extractSeconds);
		const std::vector<cv::KeyPoint> keypoints = preview ? e->features.keypoints : std::vector<cv::KeyPoint>();
		const auto t0 = Clock::now();
		const sfm::TrackedFrame& tf = sys.processExtracted(e->frame, std::move(e->features));
		sys.timings().add("track_and_map", std::chrono::duration<double>(Clock::now() - t0).count());
		if (preview)
		{
			char status[160];
			std::snprintf(status, sizeof(status), "frame %zu  %s  inliers %d  keyframes %zu  dropped %zu",
						  tf.index, tf.tracked ? sfm::toString(tf.method) : "LOST", tf.inliers, sys.numKeyFrames(),
						  source.droppedCount());
			preview->show(e->frame, keypoints, tf, status);
			if (preview->closed())
			{
				res.previewClosed = true;
				source.stop();
				queue.close();
			}
		}
		onFrame(tf);
	}
	source.stop();
	queue.close();
	producer.join();
	res.grabbed = source.grabbedCount();
	res.dropped = source.droppedCount();
	if (!producerError.empty()) throw std::runtime_error(producerError);
	return res;
}

}  // namespace keygrid::slam

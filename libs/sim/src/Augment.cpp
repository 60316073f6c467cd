#include "SequenceOutput.h"

#include <keygrid/core/TumFrameSource.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/Augment.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/sim/Simulator.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace keygrid::sim
{
namespace
{
/** Ground-truth pose at time t: linear in translation, slerp in rotation between the two
 * samples around t, if both are within maxGap of t. */
std::optional<mrpt::poses::CPose3D> poseAt(const core::Trajectory& gt, double t, double maxGap)
{
	const auto it = std::lower_bound(
		gt.begin(), gt.end(), t, [](const core::StampedPose& p, double v) { return p.t < v; });
	if (it != gt.end() && it->t == t) return it->T_world_cam;
	if (it == gt.begin() || it == gt.end()) return std::nullopt;
	const core::StampedPose& a = *(it - 1);
	const core::StampedPose& b = *it;
	if (t - a.t > maxGap || b.t - t > maxGap) return std::nullopt;
	const double s = (t - a.t) / (b.t - a.t);
	const Eigen::Isometry3d Ta = Renderer::toIsometry(a.T_world_cam),
							Tb = Renderer::toIsometry(b.T_world_cam);
	const Eigen::Quaterniond q =
		Eigen::Quaterniond(Ta.linear()).slerp(s, Eigen::Quaterniond(Tb.linear()));
	const Eigen::Vector3d p = (1 - s) * Ta.translation() + s * Tb.translation();
	const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
	mrpt::math::CMatrixDouble33 rot;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) rot(r, c) = R(r, c);
	return mrpt::poses::CPose3D(rot, mrpt::math::CVectorFixedDouble<3>({p.x(), p.y(), p.z()}));
}
}  // namespace

AugmentSummary augmentTumSequence(
	const Scene& objects, const std::string& tumDir, const std::string& outDir,
	const OutputOptions& outOpts, const AugmentOptions& opts,
	const std::function<void(std::size_t, std::size_t)>& progress, unsigned threads)
{
	using Clock = std::chrono::steady_clock;
	const auto t0 = Clock::now();
	const std::string gtPath = tumDir + "/groundtruth.txt";
	if (!mrpt::system::fileExists(gtPath))
		throw std::runtime_error(
			"augment: '" + gtPath + "' does not exist (the poses come from it)");
	core::TrajectoryReadOptions ro;
	ro.skipBadLines = true;
	const core::Trajectory gt = core::readTumTrajectory(gtPath, ro);

	core::FrameSourceOptions so;
	if (!opts.camera.empty()) so.camera = core::RgbdCamera::FromPresetOrFile(opts.camera);
	core::TumFrameSource src(tumDir, so);
	const std::size_t total = opts.maxFrames
								  ? std::min(opts.maxFrames, src.sequence().pairs().size())
								  : src.sequence().pairs().size();

	// The objects, seen through the real camera.
	Scene scene = objects;
	scene.camera = so.camera ? *so.camera : src.sequence().guessCamera();
	const Simulator sim(scene, threads);
	OutputOptions o = outOpts;
	o.voxelResolution = o.floorPlanResolution = 0;  // no ground-truth occupancy for real data
	SequenceOutput out(outDir, scene.options.name + " + " + tumDir, scene.camera, o);

	AugmentSummary sum;
	SimFrame rendered;
	core::Frame real;
	double firstT = -1, inserted = 0;
	for (std::size_t i = 0; i < total && src.next(real); i++)
	{
		if (progress) progress(i + 1, total);
		if (firstT < 0) firstT = real.timestamp;
		const auto pose = poseAt(gt, real.timestamp, opts.maxPoseGap);
		if (!pose)
		{
			sum.skippedNoPose++;
			continue;
		}
		sim.view(*pose, real.timestamp - firstT, i, rendered);
		if (real.colour.empty() || rendered.frame.colour.size() != real.colour.size())
			throw std::runtime_error(
				"augment: the frames of '" + tumDir +
				"' have no colour image of the camera's size");

		SimFrame& f = out.next();
		f.T_world_cam = *pose;
		f.frame = real;
		f.frame.colour = real.colour.clone();
		f.frame.depthRaw = real.depthRaw.clone();
		f.dynamicMask = cv::Mat::zeros(real.colour.size(), CV_8UC1);
		const float units = real.camera.depthUnits;
		std::size_t count = 0;
		for (int v = 0; v < real.colour.rows; v++)
		{
			const int* idx = rendered.render.objectIndex.ptr<int>(v);
			const float* zObj = rendered.render.depth.ptr<float>(v);
			const float* zObjMeasured = rendered.frame.depth.ptr<float>(v);
			const float* zReal = real.depth.ptr<float>(v);
			const auto* cObj = rendered.frame.colour.ptr<cv::Vec3b>(v);
			auto* cOut = f.frame.colour.ptr<cv::Vec3b>(v);
			auto* dOut = f.frame.depthRaw.ptr<std::uint16_t>(v);
			auto* mOut = f.dynamicMask.ptr<std::uint8_t>(v);
			for (int u = 0; u < real.colour.cols; u++)
			{
				// Occlusion test on the true object depth against the measured real depth.
				if (idx[u] < 0 || (zReal[u] > 0 && zReal[u] <= zObj[u])) continue;
				cOut[u] = cObj[u];
				dOut[u] = static_cast<std::uint16_t>(
					std::min(65535L, std::lround(static_cast<double>(zObjMeasured[u]) / units)));
				mOut[u] = 255;
				count++;
			}
		}
		f.frame.depth = core::depthRawToMetres(f.frame.depthRaw, units);
		cv::cvtColor(f.frame.colour, f.frame.grey, cv::COLOR_BGR2GRAY);
		inserted += count / static_cast<double>(real.colour.total());
		out.commit();
	}
	if (out.count() == 0)
		throw std::runtime_error("augment: no frame of '" + tumDir + "' has a ground-truth pose");
	out.close("ground truth of the augmented sequence: " + gtPath + " at the frame timestamps");
	sum.frames = out.count();
	sum.insertedPixelFraction = inserted / sum.frames;
	sum.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
	return sum;
}

}  // namespace keygrid::sim

#include <keygrid/sim/Random.h>
#include <keygrid/sim/Simulator.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace keygrid::sim
{
namespace
{
RenderOptions renderOptions(unsigned threads)
{
	RenderOptions o;
	o.threads = threads;
	return o;
}
}  // namespace

Simulator::Simulator(const Scene& scene, unsigned threads)
	: m_scene(scene),
	  m_renderer(scene, renderOptions(threads)),
	  m_sensor(scene.sensor, scene.camera.fx, hashKey(scene.options.seed, 0x5E4502), threads)
{
	const double maxRaw =
		std::numeric_limits<std::uint16_t>::max() * double(scene.camera.depthUnits);
	if (scene.sensor.maxRange > maxRaw)
		throw std::invalid_argument(
			"[sensor] max_range = " + std::to_string(scene.sensor.maxRange) +
			" m does not fit 16-bit depth at depth_units " +
			std::to_string(scene.camera.depthUnits));
}

void Simulator::frame(std::size_t i, SimFrame& out) const
{
	const double readout = m_scene.sensor.rollingShutterReadout;
	if (readout > 0)
	{
		// Rolling shutter: each row from the trajectory's pose at its own exposure time.
		const auto& traj = m_scene.trajectory;
		m_renderer.renderRollingShutter([&](double t) { return Renderer::toIsometry(traj.poseAt(t)); }, m_scene.frameTime(i), readout, out.render);
		finishView(m_scene.cameraPose(i), i, out);
	}
	else
		view(m_scene.cameraPose(i), m_scene.frameTime(i), i, out);
	out.frame.index = i;
	out.frame.timestamp = m_scene.timestamp(i);
}

void Simulator::view(
	const mrpt::poses::CPose3D& T_world_cam, double t, std::size_t noiseIndex, SimFrame& out) const
{
	m_renderer.render(T_world_cam, t, out.render);
	finishView(T_world_cam, noiseIndex, out);
	out.frame.timestamp = m_scene.options.startTime + t;
}

void Simulator::finishView(const mrpt::poses::CPose3D& T_world_cam, std::size_t noiseIndex, SimFrame& out) const
{
	out.T_world_cam = T_world_cam;
	core::Frame& f = out.frame;
	f.index = noiseIndex;
	f.camera = m_scene.camera;
	f.colour = out.render.colour.clone();
	cv::Mat depth;
	m_sensor.apply(noiseIndex, out.render.depth, out.render.cosIncidence, depth, f.colour);
	// Raw depth as a sensor would deliver it; metres derived from it so every reader agrees.
	const float units = m_scene.camera.depthUnits;
	f.depthRaw.create(depth.size(), CV_16UC1);
	for (int r = 0; r < depth.rows; r++)
	{
		const float* in = depth.ptr<float>(r);
		auto* o = f.depthRaw.ptr<std::uint16_t>(r);
		for (int c = 0; c < depth.cols; c++)
			o[c] = in[c] > 0
					   ? static_cast<std::uint16_t>(std::min(65535L, std::lround(in[c] / units)))
					   : 0;
	}
	f.depth = core::depthRawToMetres(f.depthRaw, units);
	cv::cvtColor(f.colour, f.grey, cv::COLOR_BGR2GRAY);

	out.dynamicMask.create(depth.size(), CV_8UC1);
	for (int r = 0; r < depth.rows; r++)
	{
		const int* idx = out.render.objectIndex.ptr<int>(r);
		auto* m = out.dynamicMask.ptr<std::uint8_t>(r);
		for (int c = 0; c < depth.cols; c++)
			m[c] = (idx[c] >= 0 && m_scene.objects[idx[c]].dynamic) ? 255 : 0;
	}
}

}  // namespace keygrid::sim

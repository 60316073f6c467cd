#pragma once
/** \file Simulator.h
 * Frame i of a scene: camera pose from the trajectory, perfect render, sensor model, packed as
 * a core::Frame exactly as a frame source would deliver it (depth = raw * depthUnits).
 */
#include <keygrid/core/Frame.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/sim/SensorModel.h>

namespace keygrid::sim
{
struct SimFrame
{
	core::Frame frame;  //!< measured colour, grey, depth, depthRaw, camera, timestamp
	mrpt::poses::CPose3D T_world_cam;  //!< ground truth, optical frame
	RenderOutput render;               //!< perfect images (render.colour is before image noise)
	cv::Mat dynamicMask;  //!< CV_8UC1, 255 where a dynamic object is the visible surface
};

class Simulator
{
   public:
	/** The scene must outlive the simulator. threads = 0: all cores. */
	explicit Simulator(const Scene& scene, unsigned threads = 0);

	/** Produces frame i (0 <= i < scene.options.frames); with [sensor]
	 * rolling_shutter_readout > 0 each row is rendered at its own exposure time. */
	void frame(std::size_t i, SimFrame& out) const;
	/** Renders and corrupts an arbitrary view; `noiseIndex` keys the noise pattern. */
	void view(
		const mrpt::poses::CPose3D& T_world_cam, double t, std::size_t noiseIndex,
		SimFrame& out) const;

	const Scene& scene() const { return m_scene; }
	const Renderer& renderer() const { return m_renderer; }
	const SensorModel& sensor() const { return m_sensor; }

   private:
	/** Sensor model and packing of out.render (already rendered) into out.frame; sets
	 * out.T_world_cam (the pose at the frame's timestamp). */
	void finishView(const mrpt::poses::CPose3D& T_world_cam, std::size_t noiseIndex, SimFrame& out) const;

	const Scene& m_scene;
	Renderer m_renderer;
	SensorModel m_sensor;
};

}  // namespace keygrid::sim

#pragma once
/** \file Scene.h
 * A synthetic world read from an INI file (see doc/simulator.md for the reference):
 * objects, their textures, the camera and its trajectory, the sensor model and what to write.
 * World frame: metres, z up (floor at z = 0 in the shipped scenes).
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/sim/CameraTrajectory.h>
#include <keygrid/sim/SceneObject.h>
#include <keygrid/sim/SensorModel.h>
#include <keygrid/sim/Texture.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::sim
{
/** The [scene] section. */
struct SceneOptions
{
	/** Scene name, written into outputs (Default: "scene") */
	std::string name{"scene"};
	/** Master seed: textures and sensor noise derive from it (Default: 1) */
	std::uint64_t seed{1};
	/** Number of frames rendered (Default: 300) */
	unsigned int frames{300};
	/** Frame rate [Hz] (Default: 30) */
	double rateHz{30.0};
	/** Timestamp of frame 0 [s, UNIX epoch] (Default: 1700000000) */
	double startTime{1700000000.0};
	/** Camera preset or INI file with a [camera] section; a [camera] section in the scene file
	 * overrides single keys (Default: "kinect") */
	std::string camera{"kinect"};
	/** Direction towards the light, world frame (Default: 0.3 0.5 1.0) */
	Eigen::Vector3d lightDirection{0.3, 0.5, 1.0};
	/** Ambient fraction of the shading, [0, 1] (Default: 0.55) */
	double ambient{0.55};

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
};

class Scene
{
   public:
	SceneOptions options;
	core::RgbdCamera camera;
	SensorOptions sensor;
	/** Empty when the file has no [trajectory] (scenes used only to augment real sequences) */
	CameraTrajectory trajectory;
	std::vector<SceneObject> objects;
	std::vector<std::shared_ptr<const Texture>> textures;

	/** Loads a scene INI. Throws std::invalid_argument naming section/key on bad values and
	 * std::runtime_error when the file cannot be read. `framesOverride` > 0 replaces
	 * [scene] frames (the trajectory is stretched to the new length). */
	static Scene loadFromFile(const std::string& path, unsigned int framesOverride = 0);
	static Scene loadFromConfig(
		const mrpt::config::CConfigFileBase& cfg, const std::string& sourceName,
		unsigned int framesOverride = 0);

	/** Time of frame i since the sequence start [s]. */
	double frameTime(std::size_t i) const { return static_cast<double>(i) / options.rateHz; }
	/** Timestamp of frame i [s]. */
	double timestamp(std::size_t i) const { return options.startTime + frameTime(i); }
	/** Ground-truth T_world_cam (optical frame) of frame i. */
	mrpt::poses::CPose3D cameraPose(std::size_t i) const { return trajectory.poseAt(frameTime(i)); }

	/** Adds an object with a texture of the given options (shared when identical). */
	void addObject(SceneObject obj, const TextureOptions& tex);
	/** Axis-aligned bounds of the static objects [m]; false when there is none. */
	bool staticBounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
};

}  // namespace keygrid::sim

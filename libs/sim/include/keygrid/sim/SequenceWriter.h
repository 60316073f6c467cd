#pragma once
/** \file SequenceWriter.h
 * Writes a simulated sequence to a folder:
 *   DIR/sequence.rawlog        CObservation3DRangeScan per frame (core::makeRgbdObservation)
 *   DIR/groundtruth.txt        TUM: T_world_cam of the optical frame, one pose per frame
 *   DIR/tum/                   rgb/ depth/ [mask/] rgb.txt depth.txt associations.txt
 *                              groundtruth.txt camera.ini (TUM RGB-D layout, depth = raw/5000 m)
 *   DIR/occupancy_voxels.txt   static-scene surface voxels (VoxelSet)
 *   DIR/floorplan.pgm/.yaml    static-scene 2D floor plan (FloorPlan, ROS map_server)
 * A monocular sequence ([output] sensor = monocular) holds no depth: the rawlog has a
 * CObservationImage per frame (core::makeImageObservation, what rawlog-grabber records for a
 * USB camera) and tum/ has rgb/ [mask/] rgb.txt groundtruth.txt camera.ini.
 */
#include <cstddef>
#include <functional>
#include <string>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::sim
{
class Scene;

/** The sensor a written sequence comes from. */
enum class RecordedSensor
{
	Rgbd,      //!< colour and depth
	Monocular  //!< colour images alone (the depth is rendered, not written)
};

/** The [output] section. */
struct OutputOptions
{
	/** Key `sensor`: `rgbd` or `monocular` (Default: rgbd) */
	RecordedSensor sensor{RecordedSensor::Rgbd};
	/** Write DIR/sequence.rawlog (Default: true) */
	bool writeRawlog{true};
	/** Write DIR/tum/ (Default: true) */
	bool writeTum{true};
	/** Write DIR/tum/mask/ PNGs, 255 = dynamic object pixel (Default: false) */
	bool writeMask{false};
	/** Store rawlog images as external PNGs in sequence_Images/ (Default: false) */
	bool externalImages{false};
	/** Ground-truth voxel size [m]; 0 disables the voxel file (Default: 0.05) */
	double voxelResolution{0.05};
	/** Floor-plan cell size [m]; 0 disables the floor plan (Default: 0.05) */
	double floorPlanResolution{0.05};
	/** Height band of the floor plan [m, world z] (Default: 0.1 .. 1.8) */
	double floorPlanZMin{0.1}, floorPlanZMax{1.8};
	/** PNG compression level 0-9 for TUM images (Default: 1: fast) */
	int pngCompression{1};

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
};

struct SequenceSummary
{
	std::size_t frames{0};
	std::size_t voxels{0}, floorPlanCells{0};
	double seconds{0};                      //!< wall time of the whole run
	double renderSeconds{0};                //!< of which rendering + sensor model
	double maxSpeed{0}, maxTurnRateDeg{0};  //!< of the camera trajectory
	double dynamicPixelFraction{0};         //!< mean over frames
	bool stopped{false};                    //!< `stop` ended the run before the last frame
};

/** Renders every frame of `scene` and writes the outputs above into `dir` (created if
 * needed). `progress(done, total)` is called after each frame when given. When `stop`
 * returns true (checked before each frame) the frames so far are written as a complete,
 * shorter sequence. On an error nothing keeps a list's or the rawlog's final name. */
SequenceSummary writeSequence(
	const Scene& scene, const std::string& dir, const OutputOptions& opts,
	const std::function<void(std::size_t, std::size_t)>& progress = {}, unsigned threads = 0,
	const std::function<bool()>& stop = {});

}  // namespace keygrid::sim

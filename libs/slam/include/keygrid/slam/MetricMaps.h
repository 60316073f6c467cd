#pragma once
/** \file MetricMaps.h
 * The metric maps of a run, configured the MRPT way: a CMultiMetricMap built from the INI's
 * [MappingApplication] section (`ismOccupancyGrid2D_count = 1`,
 * `MappingApplication_ismOccupancyGrid2D_00_creationOpts`, ...), so keygrid's plugins and MRPT's
 * own maps (octoMap, occupancyGrid, pointsMap, ...) run side by side.
 *
 * Every map is held as a maps::KeyFrameMap (one dynamic_cast when the maps are created):
 * keygrid's plugins implement it themselves and get what they were designed for (the 2D ISM
 * grid a keyframe's map points or depth, the submapped 3D grid the depth with the travelled
 * distance, the HOC map the frontend's landmarks); MRPT's own maps join through
 * maps::ObservationFedMap and get the keyframe as a CObservation3DRangeScan at its pose.
 * MetricMaps builds each event once (maps::MapKeyFrame, maps::MapCorrection, ...) and hands it
 * to every map.
 *
 * The floor frame: MetricMaps owns the run's one floor estimate (maps::FloorFrameEstimator,
 * INI section [floor]), fed with every keyframe whether or not a 2D grid is configured. Every
 * map takes it (maps::KeyFrameMap::setFloorFrame: every 2D grid as its floor, re-integrated
 * when it changes); map_3d.bt/.ply and hoc_points.ply are written in it. The
 * maps themselves (and their serialized .bin files) stay in the SLAM world, where loop
 * closures re-anchor them.
 *
 * Monocular keyframes carry no depth: the 2D and 3D grids take their map points (the landmarks
 * each observes; a ray from the camera to each), MRPT's depth-fed maps get nothing.
 * With a camera height (slam::MetricScale) the floor frame is the floor plane that estimate
 * found (useFloorFromCameraHeight), and each rescale of the map reaches the maps as a
 * correction with a scale (applyRescale): everything inserted before is rebuilt in the new
 * scale. Without one, the floor estimator runs on the map points and the maps share the map's
 * arbitrary unit. A Sim(3) loop correction gives each keyframe its own scale
 * (applyCorrection's newScales): the maps and the floor estimate scale what they hold in that
 * keyframe's camera frame by it.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CHOCPointsMap.h>
#include <keygrid/maps/FloorFrameEstimator.h>
#include <keygrid/maps/KeyFrameMap.h>
#include <keygrid/maps/ObservationFedMap.h>
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/slam/KeyFrameImageSource.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** How keyframes feed the maps ([maps] section). */
struct MapFeedOptions : public core::FieldTableOptions<MapFeedOptions>
{
	/** Input of the 2D ISM grid: "sparse" (the keyframe's map points, as in the paper) or
	 * "dense" (its depth image) (Default: sparse) */
	std::string ism2dInput{"sparse"};
	/** The maps take a keyframe's map points only when their observing keyframes see them
	 * under rays at least this far apart [deg]; for a monocular map (no depth), where a point
	 * triangulated over a short baseline lies far along its ray: on the floor it may pass the
	 * obstacle band or reach under a wall. Points with depth (RGB-D keyframes) always pass;
	 * 0 = every point (Default: 0) */
	double sparseMinParallaxDeg{0.0};
	/** After the final refinement the maps take the map points of keyframes without depth as
	 * the refined map holds them, not as they were when each keyframe was inserted: those
	 * points are triangulations that later bundle adjustments moved against their keyframe
	 * (a map distorted online would otherwise keep a distorted grid). Keyframes with depth keep
	 * their measured points (Default: true) */
	bool refreshFinalPoints{true};

	/** The [maps] keys. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "maps") const;
};

/** The frontend's landmarks as a CHOCPointsMap (histograms as the frontend kept them). */
CHOCPointsMap hocPointsFromLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc);

class MetricMaps
{
   public:
	static constexpr const char* kSection = "MappingApplication";

	/** Creates the maps `cfg` asks for. Throws std::invalid_argument naming any `<name>_count`
	 * key whose map type is unknown (MRPT itself ignores those silently) or when fewer maps
	 * were created than requested. No [MappingApplication] section: no maps. */
	MetricMaps(
		const mrpt::config::CConfigFileBase& cfg, const MapFeedOptions& feed,
		const maps::FloorFrameOptions& floor = {});

	/** Maps restored elsewhere (a stored session's snapshots, keygrid-map export), for their
	 * outputs: `T_world_floor` is the floor frame of the run that built them, if it had one. */
	static MetricMaps FromMaps(
		const std::vector<mrpt::maps::CMetricMap::Ptr>& maps, const std::optional<mrpt::poses::CPose3D>& T_world_floor);

	/** Holds pointers into its own maps: movable, not copyable. */
	MetricMaps(MetricMaps&&) = default;
	MetricMaps& operator=(MetricMaps&&) = default;
	MetricMaps(const MetricMaps&) = delete;
	MetricMaps& operator=(const MetricMaps&) = delete;

	bool empty() const { return m_maps.maps.empty(); }
	std::size_t size() const { return m_maps.maps.size(); }
	const mrpt::maps::CMultiMetricMap& maps() const { return m_maps; }

	/** The run's floor frame (given or estimated; none before the first estimate). */
	const maps::FloorFrameEstimator& floor() const { return m_floor; }
	const std::optional<mrpt::poses::CPose3D>& T_world_floor() const
	{
		return m_floorFromHeight ? m_heightFloor : m_floor.T_world_floor();
	}
	/** report.json's "floor": the estimator's (FloorFrameEstimator::toJson), or with the floor
	 * from the camera height {"source": "camera_height", "T_world_floor": ...}. */
	std::string floorJson() const;

	/** Monocular with a camera height: the floor frame is the floor plane of the camera-height
	 * estimate (applyRescale), not the floor estimator's, whose metric tolerances do not fit a
	 * map before its first metric scale. Until the first applyRescale there is no floor frame,
	 * and the 2D grids only store their keyframes. Before the first keyframe. */
	void useFloorFromCameraHeight();
	/** The map was scaled by `s` about its origin (SparseMap::rescale) and its floor plane is
	 * n . p + d = 0 (as the map is now, n towards the cameras): every map rebuilds what it
	 * holds at the keyframes' poses now in `map`, its stored points scaled by s, in the floor
	 * frame of that plane (when useFloorFromCameraHeight). Returns seconds per map name, as
	 * applyCorrection. Throws std::invalid_argument for s not positive and finite. */
	std::map<std::string, double> applyRescale(
		const sfm::SparseMap& map, double s, const Eigen::Vector3d& n_floor, double d_floor);
	/** With useFloorFromCameraHeight: the floor frame becomes that of the plane n . p + d = 0
	 * (n towards the cameras), for the next applyCorrection to re-anchor the maps on (a
	 * rescale of the newest stretch of path only). No-op before the first keyframe. */
	void setFloorFromCameraHeight(const Eigen::Vector3d& n_floor, double d_floor);

	/** Inserts keyframe `kf` (pose as now in the map) into every map and its depth samples
	 * (its map points when it has no depth) into the floor estimate (none with
	 * useFloorFromCameraHeight). `travelled` is the
	 * camera's path length so far [m]. */
	void insertKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId kf, double travelled);

	/** Where the depth of a keyframe that no longer holds it comes from (a keyframe waiting
	 * for the floor, see m_pendingDense, or inserted after its images left RAM); null: the
	 * keyframe's own. Not owned; must outlive the maps' use of it. */
	void setImageSource(const KeyFrameImageSource* images) { m_images = images; }
	/** Re-anchors the maps on corrected keyframe poses (kf id -> new T_world_cam): the floor
	 * is re-estimated under them, the 2D grid is rebuilt from its stored keyframe
	 * observations, the 3D grid morphed and merged (rebuilt from its stored map points when
	 * it was built from them). `newScales` (kf id -> factor, absent: 1) is a Sim(3)
	 * correction's scale per keyframe (monocular loop closing): what a map and the floor
	 * estimate hold in that keyframe's camera frame grows by it. `newPoints` (kf id -> world
	 * points, see refreshedMapPoints) replace what the grids hold of those keyframes.
	 * Returns seconds spent per map name ("floor" and each map that re-anchored). Throws
	 * std::invalid_argument for a factor that is not positive and finite. */
	std::map<std::string, double> applyCorrection(
		const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& newPoses,
		const std::map<sfm::KeyFrameId, double>& newScales = {},
		const std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>>& newPoints = {});
	/** With [maps] refresh_final_points: per inserted keyframe still in `map` and without
	 * depth, its map points as `map` holds them now (the points the maps take of a keyframe,
	 * see mapKeyFrame), for applyCorrection's newPoints; empty otherwise. */
	std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>> refreshedMapPoints(const sfm::SparseMap& map) const;

	/** Copies the frontend's landmarks (positions, descriptors, histograms) into every
	 * hocPointsMap; its descriptor options become `hoc` (the frontend's [hoc] section), so the
	 * histograms keep their meaning. Called at every keyframe and after the final refinement. */
	void syncLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc);

	/** Tells the maps the camera is back in mapped space (3D grid: localization mode). */
	void notifyLoopClosure();

	/** Writes each map's outputs into dir (map_2d.{pgm,yaml,png}, map_3d.bt, map_3d.ply,
	 * hoc_points.ply, and each keygrid map serialized, gz-compressed: map_2d.bin, map_3d.bin,
	 * hoc_points.bin, readable with CFileGZInputStream + archiveFrom >> map); map_3d.* and
	 * hoc_points.ply are in the floor frame when there is one (their comment line records
	 * T_world_floor), the .bin files in the SLAM world; each file appears
	 * atomically. Every file is tried; the first that cannot be written is thrown as a
	 * std::runtime_error naming it, after the others. Returns the file names written. */
	std::vector<std::string> writeOutputs(const std::string& dir) const;
	/** JSON array describing each map (class, size, outputs). */
	std::string summaryJson() const;

   private:
	MetricMaps(const MapFeedOptions& feed, const maps::FloorFrameOptions& floor) : m_feed(feed), m_floor(floor) {}

	mrpt::maps::CMultiMetricMap m_maps;
	/** m_maps.maps[i] as a keyframe map: the map itself for keygrid's plugins, an entry of
	 * m_observationFedMaps for MRPT's own. Same order as m_maps.maps. */
	std::vector<maps::KeyFrameMap*> m_keyFrameMaps;
	std::vector<std::unique_ptr<maps::ObservationFedMap>> m_observationFedMaps;
	MapFeedOptions m_feed;
	/** Per inserted keyframe: the pose the maps hold it at (updated by corrections). */
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> m_insertedPoses;
	/** Per inserted keyframe: the camera's path length at it [m]. */
	std::map<sfm::KeyFrameId, double> m_travelled;
	maps::FloorFrameEstimator m_floor;
	/** FromMaps(): the floor frame of the run that built the maps */
	std::optional<mrpt::poses::CPose3D> m_restoredFloor;
	/** See useFloorFromCameraHeight(); m_heightFloor: the frame of the last applyRescale. */
	bool m_floorFromHeight{false};
	std::optional<mrpt::poses::CPose3D> m_heightFloor;

	const KeyFrameImageSource* m_images{nullptr};
	/** Fills m_keyFrameMaps from m_maps (one dynamic_cast per map). */
	void listKeyFrameMaps();
	/** Keyframe `id` as the maps take it, as it is now in `map`. */
	/** The map points the maps take of keyframe `id` (sparse_min_parallax_deg), in the world. */
	std::vector<mrpt::math::TPoint3D> mapPointsOf(const sfm::SparseMap& map, sfm::KeyFrameId id) const;
	maps::MapKeyFrame mapKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId id, double travelled) const;
	/** The keyframe's depth, from m_images when the keyframe dropped it. */
	cv::Mat depthOf(const sfm::KeyFrame& kf) const;
	/** Hands `correction` to every map (all but the first on threads of their own); seconds per
	 * map that re-anchored, by class name. */
	std::map<std::string, double> dispatchCorrection(const maps::MapCorrection& correction);
	/** The frame map outputs are written in: the floor frame, else the SLAM world. */
	maps::ExportFrame outputFrame() const;
};

}  // namespace keygrid::slam

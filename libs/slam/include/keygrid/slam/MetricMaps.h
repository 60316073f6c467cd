#pragma once
/** \file MetricMaps.h
 * The metric maps of a run, configured the MRPT way: a CMultiMetricMap built from the INI's
 * [MappingApplication] section (`ismOccupancyGrid2D_count = 1`,
 * `MappingApplication_ismOccupancyGrid2D_00_creationOpts`, ...), so keygrid's plugins and MRPT's
 * own maps (octoMap, occupancyGrid, pointsMap, ...) run side by side.
 *
 * keygrid's maps get what they were designed for (the 2D ISM grid a keyframe's map points or
 * depth, the submapped 3D grid the depth with the travelled distance); other maps get the
 * keyframe as a CObservation3DRangeScan at its pose.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CHOCPointsMap.h>
#include <keygrid/sfm/SparseMap.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** How keyframes feed the maps ([maps] section). */
struct MapFeedOptions
{
	/** Input of the 2D ISM grid: "sparse" (the keyframe's map points, as in the paper) or
	 * "dense" (its depth image) (Default: sparse) */
	std::string ism2dInput{"sparse"};
	/** 2D grid with estimateFloorFromDepth: the floor plane is re-estimated from samples of the
	 * depth images (map points where a keyframe has no depth) of all keyframes so far (the
	 * floor is often out of view at the first one) until it is found and at least this many
	 * keyframes contributed; the grid is rebuilt when the floor changes (Default: 10) */
	int floorKeyframes{10};

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
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
	MetricMaps(const mrpt::config::CConfigFileBase& cfg, const MapFeedOptions& feed);

	bool empty() const { return m_maps.maps.empty(); }
	std::size_t size() const { return m_maps.maps.size(); }
	const mrpt::maps::CMultiMetricMap& maps() const { return m_maps; }

	/** Inserts keyframe `kf` (pose as now in the map) into every map. `travelled` is the
	 * camera's path length so far [m]. */
	void insertKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId kf, double travelled);

	/** Re-anchors the maps on corrected keyframe poses (kf id -> new T_world_cam): the 2D
	 * grid is rebuilt from its stored keyframe observations, the 3D grid morphed and merged.
	 * Returns seconds spent per map name. */
	std::map<std::string, double> applyCorrection(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& newPoses);

	/** Copies the frontend's landmarks (positions, descriptors, histograms) into every
	 * hocPointsMap; its descriptor options become `hoc` (the frontend's [hoc] section), so the
	 * histograms keep their meaning. Called at every keyframe and after the final refinement. */
	void syncLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc);

	/** Tells the maps the camera is back in mapped space (3D grid: localization mode). */
	void notifyLoopClosure();

	/** Writes each map's outputs into dir (map_2d.{pgm,yaml,png}, map_3d.bt, map_3d.ply,
	 * hoc_points.ply, and each keygrid map serialized, gz-compressed: map_2d.bin, map_3d.bin,
	 * hoc_points.bin, readable with CFileGZInputStream + archiveFrom >> map); each file appears
	 * atomically (written in DIR/.maps.tmp, then renamed);
	 * returns the file names written. */
	std::vector<std::string> writeOutputs(const std::string& dir) const;
	/** JSON array describing each map (class, size, outputs). */
	std::string summaryJson() const;

   private:
	std::vector<std::string> writeOutputsInto(const std::string& dir) const;

	mrpt::maps::CMultiMetricMap m_maps;
	MapFeedOptions m_feed;
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> m_insertedPoses;
	/** Floor estimate of the 2D grid: samples of the first keyframes (world frame), how
	 * many keyframes they came from, and the first keyframe's pose (origin and heading of the floor frame). */
	std::vector<mrpt::math::TPoint3D> m_floorPoints;
	int m_floorKeyframes{0};
	mrpt::math::TVector3D m_floorUpSum{0, 0, 0};  //!< sum of those keyframes' -y axes
	std::optional<mrpt::poses::CPose3D> m_firstKeyframePose;
};

}  // namespace keygrid::slam

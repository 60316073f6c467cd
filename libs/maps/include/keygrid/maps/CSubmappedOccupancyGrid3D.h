#pragma once
/** \file CSubmappedOccupancyGrid3D.h
 * A dense 3D log-odds occupancy grid filled from depth at keyframe poses, split into submaps
 * when camera drift would corrupt it, and morphed onto a corrected trajectory after loop
 * closure (Fig. 1 of ../shared/seeds/submapped-occupancy-grid-morphing.txt).
 *
 * Pieces (each in its own header, this class only wires them):
 *  - VoxelBlockGrid: sparse 8^3 blocks of {float log-odds, float travelled distance};
 *  - DepthFrameIntegrator: 3D DDA ray casting of a whole depth frame, one update per voxel;
 *  - ConflictDetector: FrameEvidence + the exploration / localization MappingModeMachine;
 *  - GridMorphing: inverse mapping through old / new keyframe poses and merging.
 *
 * MRPT integration: CMetricMap plugin, INI name `submappedOccupancyGrid3D`
 * (`<sect>_submappedOccupancyGrid3D_NN_creationOpts` with `resolution`, `_insertOpts` with
 * DepthIntegrationOptions + ConflictOptions + MorphingOptions + the keys of TInsertionOptions,
 * `_likelihoodOpts` with TLikelihoodOptions), versioned serialization, registered in
 * register.cpp. insertObservation() accepts CObservation3DRangeScan (each one a keyframe with
 * an automatic id, travelled distance accumulated from the poses).
 *
 * In a SLAM run (maps::KeyFrameMap, CSubmappedOccupancyGrid3D_keyframes.cpp) the grid takes
 * each keyframe's depth with the camera's path length and is morphed on corrections. A keyframe
 * without depth (monocular) brings its map points instead (insertMapPoints(): a ray from the
 * camera to each, as the ISM 2D grid takes them); a grid made of those keeps them in their
 * keyframes' camera frames and is rebuilt from them on a correction, which may then also
 * scale the world (a monocular map given metric scale) and each keyframe (a Sim(3) loop
 * correction).
 *
 * Threading: call one map from one thread at a time; integration and morphing use their own
 * worker threads (options `threads`, `morphThreads`) and give the same result for any count.
 * Documentation and measurements: doc/maps-3d.md.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/ConflictDetector.h>
#include <keygrid/maps/DepthFrameIntegrator.h>
#include <keygrid/maps/DepthScanMap.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/GridMorphing.h>
#include <keygrid/maps/KeyFrameMap.h>
#include <keygrid/maps/VoxelBlockGrid.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace keygrid
{
class CSubmappedOccupancyGrid3D : public maps::DepthScanMap, public maps::KeyFrameMap
{
	DEFINE_SERIALIZABLE(CSubmappedOccupancyGrid3D, keygrid)

   public:
	/** A keyframe integrated into the map: the pose used, the camera, where it went. */
	struct KeyframeRecord
	{
		uint64_t id{0};
		/** Pose of the optical frame used for integration (updated by morphing). */
		mrpt::poses::CPose3D T_world_cam;
		/** Camera travelled distance at this keyframe [m]. */
		double travelled{0};
		/** Submap the keyframe was integrated into. */
		std::size_t submap{0};
		core::RgbdCamera camera;
		/** Depth [m] (CV_32FC1), kept only when insertionOptions.storeKeyframeDepth. */
		cv::Mat depth;
		/** Integrated from its map points (insertMapPoints()), kept here in its camera frame
		 * (optical, map units of the last correction). */
		bool fromMapPoints{false};
		std::vector<mrpt::math::TPoint3Df> points_cam;
	};

	/** One consistent piece of the map, anchored at the keyframe that opened it. */
	struct Submap
	{
		explicit Submap(double res = 0.05) : grid(res) {}
		VoxelBlockGrid grid;
		uint64_t anchorKeyframe{0};
		/** Keyframes integrated into this submap, in insertion order. */
		std::vector<uint64_t> keyframes;
	};

	/** What insertDepthFrame() did. */
	struct InsertResult
	{
		FrameEvidence evidence;  //!< counted against the active submap before the update
		MappingMode mode{MappingMode::Exploration};
		bool conflict{false};  //!< a new submap was opened for this frame
		std::size_t submap{0};  //!< submap that received the frame
		std::string reason;  //!< mode transition / conflict cause, empty when none
		std::size_t rays{0}, voxelVisits{0};
	};

	/** Options of observation insertion (INI section `..._insertOpts`). */
	struct TInsertionOptions : public core::FieldTableOptions<TInsertionOptions>
	{
		DepthIntegrationOptions integration;
		ConflictOptions conflict;
		/** Keep each keyframe's depth image so reintegrateAtCorrectedPoses() can rebuild the
		 * grid (Default: false; costs 1.2 MB per 640x480 keyframe) */
		bool storeKeyframeDepth{false};
		/** Record every observation passed to insertObservation() as a keyframe (Default: true) */
		bool observationsAreKeyframes{true};

		/** The INI keys of integration, conflict and this struct, with description and rule. */
		core::OptionFields fields();
		/** Throws std::invalid_argument naming [section], key and value on a bad value. */
		void validate(const std::string& section = "insertOpts") const;
	};

	/** Options of computeObservationLikelihood (INI section `..._likelihoodOpts`). */
	struct TLikelihoodOptions : public core::FieldTableOptions<TLikelihoodOptions>
	{
		/** Use every N-th pixel in u and v (Default: 10) */
		unsigned decimation{10};
		/** Ignore points farther than this [m] (Default: 4 m) */
		double maxRange{4.0};
		/** Floor of the per-point occupancy probability (Default: 0.05) */
		double minProbability{0.05};

		core::OptionFields fields();
	};

	TInsertionOptions insertionOptions;
	MorphingOptions morphingOptions;
	TLikelihoodOptions likelihoodOptions;

	/** Voxel edges accepted [m]: finer than any RGB-D camera's depth step at 1 m is only
	 * memory and time (a ray of maxRange crosses maxRange / resolution voxels); coarser than
	 * a room is no map. */
	static constexpr double kMinResolution = 0.005, kMaxResolution = 10.0;

	/** \param resolution Voxel edge [m] in [kMinResolution, kMaxResolution] (Default: 0.05 m);
	 * std::invalid_argument otherwise. */
	explicit CSubmappedOccupancyGrid3D(double resolution = 0.05);

	double resolution() const { return m_resolution; }
	/** Changes the voxel size; clears the map. */
	void setResolution(double resolution);

	/** @name Integration
	 * @{ */
	/** Integrates a depth image [m] (CV_32FC1) seen by `cam` at T_world_cam (optical frame)
	 * whose camera has travelled `travelled` m. With a keyframe id the frame is recorded as a
	 * keyframe (pose, camera, submap, optional depth); without one it is a tracked frame that
	 * only updates the grid. Evaluates the frame against the active submap, advances the mode
	 * machine and opens a new submap (anchored at this keyframe, or at the last keyframe for a
	 * tracked frame) on a conflict. Throws std::invalid_argument on a repeated keyframe id or
	 * bad image. */
	InsertResult insertDepthFrame(
		const cv::Mat& depth_m, const core::RgbdCamera& cam,
		const mrpt::poses::CPose3D& T_world_cam, double travelled,
		std::optional<uint64_t> keyframeId);
	/** Integrates a keyframe's map points [world] seen from T_world_cam (a keyframe without
	 * depth, e.g. monocular): a 3D DDA ray from the camera centre to each point, the voxels
	 * before it free and its voxel occupied (DepthFrameIntegrator::castPoints: the ranges,
	 * clamping and endpoint discretization of depth frames), through the same evaluation
	 * against the active submap, mode machine and submap opening as insertDepthFrame(). The
	 * keyframe is recorded with its points in its camera frame (`cam` only serves the view
	 * cone should the grid be morphed). Throws std::invalid_argument on a repeated keyframe id
	 * or a bad travelled distance. */
	InsertResult insertMapPoints(
		uint64_t keyframeId, const mrpt::poses::CPose3D& T_world_cam,
		const std::vector<mrpt::math::TPoint3D>& points_world, const core::RgbdCamera& cam, double travelled);
	/** Signals a loop closure: the next frame is integrated in localization mode. */
	void notifyLoopClosure() override { m_modeMachine.notifyRevisit(); }
	/** Signals a relocalization: same effect as a loop closure. */
	void notifyRelocalization() { m_modeMachine.notifyRevisit(); }
	MappingMode mode() const { return m_modeMachine.mode(); }
	/** @} */

	/** @name Submaps and keyframes
	 * @{ */
	std::size_t numSubmaps() const { return m_submaps.size(); }
	const Submap& submap(std::size_t i) const { return m_submaps.at(i); }
	std::size_t activeSubmap() const { return m_active; }
	const std::map<uint64_t, KeyframeRecord>& keyframes() const { return m_keyframes; }
	/** Log-odds at p over all submaps (the newest submap that knows the voxel wins);
	 * nullopt when no submap knows it. */
	std::optional<float> logOddsAt(const mrpt::math::TPoint3D& p) const;
	/** One grid of all submaps, newest submap winning where they overlap (a view for export,
	 * not a merge: merging needs morphAndMergeSubmaps()). */
	VoxelBlockGrid fusedGrid() const;
	/** Centres of the voxels of fusedGrid() with log-odds > 0. */
	std::vector<mrpt::math::TPoint3D> occupiedVoxelCentres() const;
	/** CMetricMap: no submap holds a voxel block. */
	bool isEmpty() const override;
	/** Resolution, submaps, keyframes, blocks and mode in one line. */
	std::string asString() const override;
	/** @} */

	/** @name Trajectory correction
	 * @{ */
	/** Grid morphing (paper Fig. 1b): moves every submap onto the corrected keyframe poses and
	 * merges them into one submap; no depth is re-integrated. Keyframes absent from `corr` keep
	 * their pose; ids the map does not know are ignored. The old pose of a keyframe is the one
	 * recorded when it was integrated (what the grid was built with), not corr's
	 * T_world_cam_old. Keyframe poses are updated to the new ones. */
	MorphingStats morphAndMergeSubmaps(const TrajectoryCorrection& corr);
	/** Keyframe `id`, recorded as `rec`, as morphAndMerge() takes it: from the pose it was
	 * integrated at to T_world_cam_new. */
	static MorphKeyframe morphKeyframe(uint64_t id, const KeyframeRecord& rec, const mrpt::poses::CPose3D& T_world_cam_new);

	struct ReintegrationStats
	{
		std::size_t frames{0};
		double seconds{0};
	};
	/** Baseline (c): rebuilds one grid by re-integrating every keyframe's stored depth at its
	 * corrected pose. Requires insertionOptions.storeKeyframeDepth (throws std::logic_error
	 * naming the first keyframe without depth otherwise). */
	ReintegrationStats reintegrateAtCorrectedPoses(const TrajectoryCorrection& corr);
	/** True when every keyframe was integrated from its map points (and there is one). */
	bool builtFromMapPoints() const;
	/** A grid built from map points (builtFromMapPoints()): the world scaled by `worldScale`
	 * about its origin (every keyframe's stored points and translation, its travelled
	 * distance), then each keyframe of `corr` at its corrected pose with its points scaled by
	 * its PoseCorrection::scale, and the keyframes of `newPoints` with those world points
	 * instead of their stored ones; the keyframes' points re-integrated, in id order, into one
	 * submap. Throws std::logic_error for a grid not built from map points. */
	ReintegrationStats rebuildFromMapPoints(
		const TrajectoryCorrection& corr, double worldScale = 1.0,
		const std::map<uint64_t, std::vector<mrpt::math::TPoint3D>>& newPoints = {});
	/** @} */

	/** @name In a SLAM run (maps::KeyFrameMap)
	 * @{ */
	/** insertDepthFrame() of the keyframe's depth at its pose and path length; without depth,
	 * insertMapPoints() of its map points (nothing when it has none either). */
	void insertKeyFrame(const maps::MapKeyFrame& kf, const maps::KeyFrameFeed& feed) override;
	/** The grid is made of depth, not of the frontend's landmarks. */
	void syncLandmarks(const maps::LandmarkSource&) override {}
	/** A grid built from map points: rebuildFromMapPoints() with the correction's scales.
	 * Otherwise morphAndMergeSubmaps(correction.poses), which cannot scale: throws
	 * std::invalid_argument for a scale other than 1 (world or keyframe) on a grid with
	 * keyframes. False when there is nothing to re-anchor (no keyframes and a scale). */
	bool applyCorrection(const maps::MapCorrection& correction) override;
	// notifyLoopClosure(): see Integration.
	/** The grid stays in the SLAM world; its exports take the frame they are written in. */
	void setFloorFrame(const std::optional<mrpt::poses::CPose3D>&) override {}
	/** map_3d<suffix>.bt (saveAsOctomapBinary) and .ply (saveOccupiedAsPly), in out.frame(),
	 * and .bin (this map serialized, gz-compressed, in the SLAM world). */
	void writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const override;
	/** "submaps", "memory_bytes" (memoryBytes()) and "keyframes". */
	std::string summaryJsonFields() const override;
	/** @} */

	/** @name Exports
	 * @{ */
	/** Writes fusedGrid() as an OctoMap binary tree (.bt, maximum-likelihood occupied / free
	 * leaves at this resolution). Throws std::runtime_error when the file cannot be written.
	 * In another frame than the world (`frame`, e.g. the floor frame), the grid is resampled
	 * at the same resolution: each voxel of the output lattice takes the value of the world
	 * voxel that holds its centre (nearest neighbour); frame.comment becomes a comment line
	 * of the .bt header, which OctoMap's reader skips. */
	void saveAsOctomapBinary(const std::string& path, const maps::ExportFrame& frame = {}) const;
	/** Writes getVisualizationInto() as a SceneViewer3D scene (.3Dscene). Throws
	 * std::runtime_error when the file cannot be written. */
	void saveAs3DScene(const std::string& path) const;
	/** Writes the occupied voxel centres as an ASCII PLY point cloud, mapped into `frame`
	 * (each centre moved exactly; frame.comment is a PLY comment line). */
	void saveOccupiedAsPly(const std::string& path, const maps::ExportFrame& frame = {}) const;
	/** Heap bytes of all submap grids (VoxelBlockGrid::memoryBytes) plus stored depth and map
	 * points. */
	std::size_t memoryBytes() const;
	/** CMetricMap: writes `<prefix>.bt`, `<prefix>_occupied.ply` and `<prefix>.3Dscene`. */
	void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
	/** Occupied voxel centres as one mrpt::opengl::CPointCloud, coloured by height. */
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const override;
	/** @} */

   protected:
	void internal_clear() override;
	// maps::DepthScanMap
	bool insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) override;
	/** Any depth scan (an empty grid scores unknown voxels). */
	bool canComputeDepthScanLikelihood(const mrpt::obs::CObservation3DRangeScan&) const override { return true; }
	double depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const override;

   private:
	DepthFrameIntegrator& integrator();
	/** Throws std::invalid_argument (naming `caller`) for a known keyframe id or a bad
	 * travelled distance. */
	void checkNewFrame(const char* caller, std::optional<uint64_t> keyframeId, double travelled) const;
	/** The rest of an insertion: `upd` against the active submap, mode machine, a new submap
	 * on a conflict, the update, and `record` (when given) filed as a keyframe. */
	InsertResult integrateFrame(const FrameVoxelUpdates& upd, double travelled, std::optional<KeyframeRecord> record);

	double m_resolution{0.05};
	std::vector<Submap> m_submaps;
	std::size_t m_active{0};
	std::map<uint64_t, KeyframeRecord> m_keyframes;
	std::optional<uint64_t> m_lastKeyframe;
	MappingModeMachine m_modeMachine;
	/** insertObservation() bookkeeping: last camera pose, accumulated travel, next id. */
	std::optional<mrpt::poses::CPose3D> m_lastObsCamPose;
	double m_obsTravelled{0};
	uint64_t m_nextObsKeyframeId{0};
	/** Integrator with its caches (ray table); a copy of the map starts with an empty cache. */
	struct IntegratorCache
	{
		IntegratorCache() = default;
		IntegratorCache(const IntegratorCache&) {}
		IntegratorCache& operator=(const IntegratorCache&)
		{
			ptr.reset();
			return *this;
		}
		IntegratorCache(IntegratorCache&&) = default;
		IntegratorCache& operator=(IntegratorCache&&) = default;
		std::unique_ptr<DepthFrameIntegrator> ptr;
	};
	IntegratorCache m_integrator;

	MAP_DEFINITION_START(CSubmappedOccupancyGrid3D)
	/** Voxel edge [m] (Default: 0.05 m); INI section `_creationOpts`, key `resolution` */
	double resolution{0.05};
	/** The `_creationOpts` keys (resolution), with description and rule. */
	core::OptionFields creationFields();
	keygrid::CSubmappedOccupancyGrid3D::TInsertionOptions insertionOpts;
	keygrid::MorphingOptions morphingOpts;
	keygrid::CSubmappedOccupancyGrid3D::TLikelihoodOptions likelihoodOpts;
	MAP_DEFINITION_END(CSubmappedOccupancyGrid3D)
};

}  // namespace keygrid

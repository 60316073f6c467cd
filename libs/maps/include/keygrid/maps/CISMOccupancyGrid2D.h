#pragma once
/** \file CISMOccupancyGrid2D.h
 * A 2D navigation occupancy grid filled from visual-SLAM keyframes with the erf inverse sensor
 * model of Lu & Wang (2018). MRPT CMetricMap plugin registered as "ismOccupancyGrid2D".
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/maps/DepthScanMap.h>
#include <keygrid/maps/FloorPlaneEstimator.h>
#include <keygrid/maps/InverseSensorModel.h>
#include <keygrid/maps/KeyFrameMap.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace keygrid
{
/** Tri-state classification of a cell. */
enum class CellState : uint8_t
{
	Unknown = 0,
	Free = 1,
	Occupied = 2
};

/** 2D occupancy grid in the floor plane, updated in log-odds with the practical (erf) ISM.
 *
 * Frames: the grid lives in the floor frame F (z up, z = 0 on the floor); its pose in the
 * world is insertionOptions.T_world_floor, or a RANSAC estimate of the floor plane from the
 * first depth image when insertionOptions.estimateFloorFromDepth is set (TUM's world frame is
 * not gravity aligned), or set from outside (setExternalFloorPose: keygrid-slam hands every
 * grid the run's one floor frame). A 3D point p_F is an obstacle when obstacleMinHeight <= z <=
 * obstacleMaxHeight, floor when |z| <= floorTolerance (it then only clears space), and ignored
 * otherwise. Every kept point casts a 2D ray from the camera's footprint to the point's
 * footprint; the cells on it are updated with l += logit(ISM(r)) - l0. With the default
 * freeSpaceModel = heightBand the update goes to the height slices of the obstacle band that
 * the 3D ray crosses in each cell (and to the cell's ground clearance where the ray is below
 * obstacleMinHeight); a cell reads occupied when any slice holds obstacle evidence and free only
 * when its ground clearance was seen free, so rays passing above or below an obstacle never
 * erase it. freeSpaceModel = paper is the paper's model (every cell before a hit is free).
 *
 * Storage: float log-odds per cell in a grid that grows on demand (in steps of
 * creationOptions.growthMargin) from the creation extent, because a SLAM map's extent is not
 * known in advance; cells outside the grid read as unknown.
 *
 * Inputs: insertKeyframePoints() (sparse map points, the paper's input), insertKeyframeDepth()
 * and insertObservation(CObservation3DRangeScan) (dense depth, reduced to one ray per endpoint
 * cell). Each keyframe's rays are kept in the camera frame, so applyTrajectoryCorrection()
 * rebuilds the grid under corrected poses after a loop closure.
 *
 * In a SLAM run (maps::KeyFrameMap, CISMOccupancyGrid2D_keyframes.cpp) the grid takes the
 * run's floor frame, its keyframes' map points or depth, and rebuilds on corrections.
 */
class CISMOccupancyGrid2D : public maps::DepthScanMap, public maps::KeyFrameMap
{
	DEFINE_SERIALIZABLE(CISMOccupancyGrid2D, keygrid)

   public:
	/** Creation options: the grid geometry. */
	struct TCreationOptions : public core::FieldTableOptions<TCreationOptions>
	{
		/** Cell size [m] (Default: 0.05 m) */
		double resolution{0.05};
		/** Initial extent in the floor frame [m] (Default: -5..5 x -5..5 m) */
		double min_x{-5.0}, max_x{5.0}, min_y{-5.0}, max_y{5.0};
		/** Extra border added when the grid has to grow [m] (Default: 2 m) */
		double growthMargin{2.0};

		/** The INI keys (MRPT's COccupancyGridMap2D names), with description and rule. */
		core::OptionFields fields();
		/** Throws std::invalid_argument naming [section], key and value on a bad value. */
		void validate(const std::string& section = "creationOpts") const;
	};

	/** Ray traversal used to distribute the ISM over cells. */
	enum class RayTraversal : uint8_t
	{
		Bresenham = 0,
		AntiAliased = 1  ///< Xiaolin Wu: two cells per step, weights sum to one
	};

	/** How rays make free space. */
	enum class FreeSpaceModel : uint8_t
	{
		/** Height-aware: each column keeps the log-odds of height slices of the obstacle band and
		 * of its ground clearance (below obstacleMinHeight). A ray updates only the slices it
		 * crosses in a column, so obstacle evidence is never erased by rays passing above or
		 * below it; a column is free only when its clearance was seen free and no slice holds
		 * obstacle evidence. */
		HeightBand = 0,
		/** Lu & Wang (2018): every 2D cell before a hit is free, whatever the ray's height there
		 * (a ray to a wall above a table frees the table's cells). */
		Paper = 1
	};

	/** Insertion options: ISM, noise, height band, floor frame, traversal, thresholds. */
	struct TInsertionOptions : public core::FieldTableOptions<TInsertionOptions>
	{
		/** Ideal-model occupancy before the band (Default: 0.30) */
		double pFree{0.30};
		/** Ideal-model occupancy inside the band (Default: 0.90) */
		double pOccupied{0.90};
		/** Prior occupancy p0, l0 = logit(p0); also the value of unknown cells (Default: 0.5) */
		double pPrior{0.5};
		/** Occupied band width L [m]; 0 = the cell diagonal, resolution*sqrt(2) (Default: 0) */
		double bandWidth{0.0};
		/** Range noise model: "constant" or "kinect" (Default: kinect) */
		maps::RangeNoiseModel rangeNoise{maps::RangeNoiseModel::Kinect};
		/** sigma of the "constant" model [m] (Default: 0.02 m) */
		double sigmaConstant{0.02};
		/** Log-odds clamping limits (Default: -2.0 and 3.5, i.e. p in [0.12, 0.97]) */
		double logOddsMin{-2.0}, logOddsMax{3.5};
		/** Points whose horizontal distance to the camera exceeds this are ignored [m]
		 * (Default: 4.5 m) */
		double maxRange{4.5};
		/** Obstacle height band above the floor [m] (Default: 0.10 .. 1.80 m) */
		double obstacleMinHeight{0.10}, obstacleMaxHeight{1.80};
		/** Points within +-this of the floor are floor: they clear their ray [m]
		 * (Default: 0.04 m) */
		double floorTolerance{0.04};
		/** A floor point's ray clears space up to this short of the point [m]: the cells at a
		 * point placed with an error of a few cm (a monocular map point: its triangulation,
		 * its keyframe's pose) may lie under the obstacle whose foot the point really is;
		 * the floor right before an obstacle is then only cleared by points beyond it (Default:
		 * 0 m: the whole ray, for depth images) */
		double floorRayMargin{0.0};
		/** Pose of the floor frame (z up) in the world (Default: identity) */
		mrpt::poses::CPose3D T_world_floor;
		/** Estimate the floor plane by RANSAC from the first depth image instead of
		 * T_world_floor (Default: false) */
		bool estimateFloorFromDepth{false};
		/** "Up" direction in the world for that estimate, INI "floorUpHint = x y z"; (0,0,0)
		 * means the first camera's -y axis (camera held upright) (Default: 0 0 0) */
		mrpt::math::TVector3D floorUpHint{0, 0, 0};
		/** RANSAC parameters of that estimate */
		maps::FloorPlaneRansacOptions floorRansac;
		/** A new external floor frame (setFloorFrame()) re-integrates the keyframes only when
		 * it moves some point of the grid's box (its extent, from -floorTolerance to
		 * obstacleMaxHeight) by more than this [m]; a smaller change keeps the floor frame the
		 * cells were built in. 0: every change re-integrates (Default: 0.01 m) */
		double floorReanchorShift{0.01};
		/** Free-space model: "heightBand" or "paper" (Default: heightBand) */
		FreeSpaceModel freeSpaceModel{FreeSpaceModel::HeightBand};
		/** heightBand: thickness of the height slices of the obstacle band [m] (Default: 0.05 m) */
		double bandSliceHeight{0.05};
		/** Ray traversal: "bresenham" or "antialiased" (Default: bresenham) */
		RayTraversal rayTraversal{RayTraversal::Bresenham};
		/** Dense depth: use every n-th pixel in rows and columns; 2 keeps several pixels per
		 * 5 cm cell of a 640x480 Kinect image out to maxRange (Default: 2) */
		int depthDecimation{2};
		/** Dense depth: minimum points in an endpoint cell before it casts an obstacle ray,
		 * rejects speckle (Default: 2) */
		int minPointsPerCell{2};
		/** Tri-state thresholds on the occupancy probability: p >= occupied -> Occupied,
		 * p <= free -> Free, else Unknown (Default: 0.65 and 0.35) */
		double occupiedThreshold{0.65}, freeThreshold{0.35};

		/** The ISM shape these options define at a given resolution (L = 0 -> diagonal). */
		maps::IsmShape ismShape(double resolution) const;

		/** The INI keys (floorRansac's prefixed "floorRansac_"), with description and rule. */
		core::OptionFields fields();
		/** Throws std::invalid_argument naming [section], key and value on a bad value. */
		void validate(const std::string& section = "insertOpts") const;
	};

	/** Likelihood options for computeObservationLikelihood(CObservation3DRangeScan). */
	struct TLikelihoodOptions : public core::FieldTableOptions<TLikelihoodOptions>
	{
		/** Use every n-th depth pixel in rows and columns (Default: 8) */
		int decimation{8};
		/** Probability floor mixed into each point's cell occupancy (Default: 0.05) */
		double outlierProbability{0.05};

		core::OptionFields fields();
	};

	/** One keyframe's stored rays: camera pose and ray endpoints in the optical frame. */
	struct KeyframeRays
	{
		mrpt::poses::CPose3D T_world_cam;
		std::vector<mrpt::math::TPoint3Df> points_cam;
	};

	TCreationOptions creationOptions;
	TInsertionOptions insertionOptions;
	TLikelihoodOptions likelihoodOptions;

	/** An empty grid with default options. */
	CISMOccupancyGrid2D();
	/** An empty grid with the given geometry (validated). */
	explicit CISMOccupancyGrid2D(const TCreationOptions& creation);

	/** @name Inputs
	 * @{ */
	/** Sparse input (the paper's): a keyframe's pose and its map points in world coordinates.
	 * Stores the points (camera frame) under `keyframeId` (replacing an earlier entry) and
	 * updates the grid. Returns false if the floor frame is still unknown (estimateFloorFromDepth
	 * before any depth image): the points are then only stored, and enter the grid at the next
	 * applyTrajectoryCorrection(). */
	bool insertKeyframePoints(
		uint64_t keyframeId, const mrpt::poses::CPose3D& T_world_cam,
		const std::vector<mrpt::math::TPoint3D>& points_world);
	/** Dense input: a depth image (MRPT depth frame, obs.sensorPose = T_robot_depth) with the
	 * keyframe camera pose. Estimates the floor first if so configured. The depth is reduced to
	 * one ray per endpoint cell, and those rays are stored under `keyframeId`. */
	bool insertKeyframeDepth(
		uint64_t keyframeId, const mrpt::poses::CPose3D& T_world_cam,
		const mrpt::obs::CObservation3DRangeScan& obs);
	/** Rebuilds the grid from the stored keyframes, with `newPoses` replacing the poses of the
	 * keyframes it names (others keep theirs). Returns the wall time taken [s], also kept in
	 * lastRebuildSeconds(). Unknown ids throw std::out_of_range. */
	double applyTrajectoryCorrection(const std::map<uint64_t, mrpt::poses::CPose3D>& newPoses);
	double lastRebuildSeconds() const { return m_lastRebuildSeconds; }
	const std::map<uint64_t, KeyframeRays>& keyframes() const { return m_keyframes; }
	/** Largest move of a point of the grid's box (extent x [-floorTolerance,
	 * obstacleMaxHeight] in the floor frame) when the floor frame changes to T_world_floor:
	 * the distance between its coordinates in the two frames [m]. */
	double floorFrameShift(const mrpt::poses::CPose3D& T_world_floor) const;
	/** Sets the floor frame from a plane estimate on given world points (e.g. SLAM map points).
	 * The "up" hint is insertionOptions.floorUpHint, else `upHint` when given (e.g. the mean -y
	 * of several cameras), else -y of the camera; the floor frame's origin is the camera
	 * footprint and its x axis the camera heading. */
	bool estimateFloorFromPoints(
		const std::vector<mrpt::math::TPoint3D>& points_world,
		const mrpt::poses::CPose3D& T_world_cam,
		const std::optional<mrpt::math::TVector3D>& upHint = std::nullopt);
	/** True once the floor frame is known (always when estimateFloorFromDepth is false and no
	 * external floor is expected). */
	bool floorKnown() const
	{
		return m_floorExternal ? m_floorEstimated : !insertionOptions.estimateFloorFromDepth || m_floorEstimated;
	}
	/** The floor frame comes from outside (keygrid-slam: the run's one floor frame,
	 * maps::FloorFrameEstimator) and is not known yet: floorKnown() is false until
	 * setExternalFloorPose(), and the grid never estimates a floor itself (its T_world_floor,
	 * estimateFloorFromDepth, floorUpHint and floorRansac_* options are then unused). */
	void expectExternalFloorPose();
	/** Sets the floor frame from outside (see expectExternalFloorPose(), which this implies).
	 * Keyframes integrated before keep the old floor until applyTrajectoryCorrection(). */
	void setExternalFloorPose(const mrpt::poses::CPose3D& T_world_floor);
	bool externalFloor() const { return m_floorExternal; }
	/** @} */

	/** @name In a SLAM run (maps::KeyFrameMap)
	 * @{ */
	/** GridInput::Depth and a keyframe with depth: insertKeyframeDepth(), after the keyframes
	 * kept aside until the floor frame was known (the depth is reduced in the floor frame);
	 * otherwise insertKeyframePoints() with its map points (stored also before the floor is
	 * known, integrated then). */
	void insertKeyFrame(const maps::MapKeyFrame& kf, const maps::KeyFrameFeed& feed) override;
	/** The grid reads a keyframe's own map points at insertion, not the landmark set. */
	void syncLandmarks(const maps::LandmarkSource&) override {}
	/** Scales the stored rays (camera frame) by correction.scale (with every pose's
	 * translation) and each named keyframe's rays by its own PoseCorrection::scale, replaces
	 * the rays of the keyframes in correction.points_world by those points (in the keyframe's
	 * corrected frame), takes correction.T_world_floor when given, then rebuilds under the corrected poses of its
	 * keyframes (applyTrajectoryCorrection()); false while the floor frame is unknown (nothing
	 * integrated yet). Throws std::invalid_argument, before changing anything, for a factor
	 * that is not positive and finite. */
	bool applyCorrection(const maps::MapCorrection& correction) override;
	/** The 2D grid has no mapping mode a loop closure would change. */
	void notifyLoopClosure() override {}
	/** The run's floor frame becomes the grid's (setExternalFloorPose(); nullopt:
	 * expectExternalFloorPose()) and the keyframes integrated so far are integrated again in
	 * it, unless it moves no point of the grid by more than floorReanchorShift (see
	 * floorFrameShift()): the grid then keeps its floor frame. The first call refuses a floor of the grid's own (insertionOptions.T_world_floor
	 * without estimateFloorFromDepth), naming the INI key. */
	void setFloorFrame(const std::optional<mrpt::poses::CPose3D>& T_world_floor) override;
	/** map_2d<suffix>.yaml + .pgm (saveAsRosMapServer), .png (saveAsImage) and .bin (this map
	 * serialized, gz-compressed), all in the grid's floor frame. */
	void writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const override;
	/** "cells", "states" (countStates()) and "keyframes". */
	std::string summaryJsonFields() const override;
	/** @} */

	/** @name Cell access (cell indices; (0,0) is the cell at (xMin, yMin))
	 * @{ */
	double resolution() const { return m_resolution; }
	double xMin() const { return m_xMin; }
	double yMin() const { return m_yMin; }
	double xMax() const { return m_xMin + m_sizeX * m_resolution; }
	double yMax() const { return m_yMin + m_sizeY * m_resolution; }
	int sizeX() const { return m_sizeX; }
	int sizeY() const { return m_sizeY; }
	int x2idx(double x) const { return static_cast<int>(std::floor((x - m_xMin) / m_resolution)); }
	int y2idx(double y) const { return static_cast<int>(std::floor((y - m_yMin) / m_resolution)); }
	double idx2x(int cx) const { return m_xMin + (cx + 0.5) * m_resolution; }
	double idx2y(int cy) const { return m_yMin + (cy + 0.5) * m_resolution; }
	bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < m_sizeX && cy < m_sizeY; }
	/** Log-odds of a cell (l0 outside the grid). */
	float logOdds(int cx, int cy) const;
	/** Occupancy probability of a cell (pPrior outside the grid). */
	double occupancy(int cx, int cy) const;
	/** Tri-state by the insertion thresholds. */
	CellState cellState(int cx, int cy) const;
	/** Tri-state at a floor-frame position [m]. */
	CellState stateAt(double x, double y) const { return cellState(x2idx(x), y2idx(y)); }
	/** Number of cells in each state: {unknown, free, occupied}. */
	std::array<size_t, 3> countStates() const;
	/** CMetricMap: no cell updated yet (every log-odds 0). */
	bool isEmpty() const override;
	/** Size, bounds, cell states and keyframes in one line. */
	std::string asString() const override;
	/** The floor frame in use: the external one when set, the estimate when
	 * estimateFloorFromDepth, else T_world_floor. */
	const mrpt::poses::CPose3D& floorPose() const
	{
		return m_floorExternal || insertionOptions.estimateFloorFromDepth ? m_T_world_floorEstimate
																		  : insertionOptions.T_world_floor;
	}
	/** @} */

	/** @name Exports
	 * @{ */
	/** ROS map_server pair: `<yamlPath>` and the .pgm next to it (same stem). Trinary:
	 * occupied 0, free 254, unknown 205; origin = (xMin, yMin, 0) in the floor frame. Throws on
	 * I/O errors. */
	void saveAsRosMapServer(const std::string& yamlPath) const;
	/** Grey PNG (or any format by extension): 255 * (1 - p), i.e. black = occupied; y up. */
	void saveAsImage(const std::string& file) const;
	/** The same grid as MRPT's COccupancyGridMap2D (its cells store p(free) = 1 - p). */
	mrpt::maps::COccupancyGridMap2D toOccupancyGridMap2D() const;
	/** CMetricMap: writes `<prefix>.yaml` + `.pgm` (saveAsRosMapServer) and `<prefix>.png`
	 * (saveAsImage). */
	void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
	/** toOccupancyGridMap2D()'s textured plane at the floor pose (when enableSaveAs3DObject). */
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const override;
	/** @} */

   protected:
	void internal_clear() override;
	// maps::DepthScanMap
	bool insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) override;
	/** Depth scans that hold a range image. */
	bool canComputeDepthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan) const override { return scan.hasRangeImage; }
	double depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const override;

   private:
	double m_resolution{0.05};
	double m_xMin{0}, m_yMin{0};
	int m_sizeX{0}, m_sizeY{0};
	std::vector<float> m_logOdds;  ///< row-major, index cx + cy * m_sizeX; heightBand: the column value
	/** heightBand: per cell, bandStride() values: [0] ground clearance, [1..K] the band's height
	 * slices from obstacleMinHeight up (log-odds relative to the prior); empty in paper mode. */
	std::vector<float> m_band;
	int m_bandSlices{0};  ///< K, the number of height slices m_band was laid out for
	mrpt::poses::CPose3D m_T_world_floorEstimate;  ///< RANSAC estimate, if m_floorEstimated
	bool m_floorEstimated{false};
	/** The floor is set from outside (setExternalFloorPose) into m_T_world_floorEstimate. */
	bool m_floorExternal{false};
	std::map<uint64_t, KeyframeRays> m_keyframes;
	/** insertKeyFrame() with depth input: keyframes that arrived before the floor frame. */
	std::vector<uint64_t> m_waitingForFloor;
	/** INI section prefix the grid was created from (`<sect>_ismOccupancyGrid2D_NN`), to name
	 * keys in errors; empty when built in code. */
	std::string m_optionSection;
	uint64_t m_nextAutoKeyframeId{1ULL << 62};  ///< ids for insertObservation() inputs
	double m_lastRebuildSeconds{0};
	/** Per-insertion scratch: the one update each cell (heightBand: each slice of a cell in the
	 * keyframe's BandWindow) gets from the current keyframe, and the indices touched. */
	std::vector<float> m_scratch, m_bandScratch;
	std::vector<int> m_touched;
	std::vector<size_t> m_bandTouched;
	/** heightBand scratch: the slots of a cell's column that get the exact-free update. */
	struct FreeColumn
	{
		uint64_t slices{0};  ///< bit k: band slice k
		bool clearance{false};  ///< the ground-clearance slot
	};
	std::vector<FreeColumn> m_freeColumns;
	std::vector<size_t> m_freeTouched;

	bool heightBand() const { return insertionOptions.freeSpaceModel == FreeSpaceModel::HeightBand; }
	/** Number of height slices the insertion options ask for. */
	int bandSlicesWanted() const;
	/** (Re)allocates m_band for the current grid size and options, cleared. */
	void resetBand();
	/** The cells [x0, x0 + w) x [y0, y0 + h) of the grid that one keyframe's rays can reach:
	 * m_bandScratch holds their slices (window cell index * stride + slot). */
	struct BandWindow
	{
		int x0{0}, y0{0}, w{0}, h{0};
		size_t cells() const { return static_cast<size_t>(w) * static_cast<size_t>(h); }
		bool contains(int cx, int cy) const { return cx >= x0 && cx < x0 + w && cy >= y0 && cy < y0 + h; }
		size_t index(int cx, int cy) const { return static_cast<size_t>(cx - x0) + static_cast<size_t>(cy - y0) * static_cast<size_t>(w); }
		size_t gridCell(size_t windowCell, size_t sizeX) const
		{
			const size_t ww = static_cast<size_t>(w);
			return static_cast<size_t>(x0) + windowCell % ww + (static_cast<size_t>(y0) + windowCell / ww) * sizeX;
		}
	};
	/** The window over the floor-frame box [x0,x1]x[y0,y1] (grown to contain it) with a margin
	 * of two cells for the traversals' neighbours, clipped to the grid. */
	BandWindow bandWindow(double x0, double x1, double y0, double y1) const;
	/** The column log-odds of a cell from its band values: the strongest obstacle evidence in
	 * the band if any is positive, else the ground clearance. */
	float columnLogOdds(size_t cell) const;

	void resetGeometry(const TCreationOptions& c);
	/** Grows the grid (keeping contents) to cover [x0,x1]x[y0,y1] of the floor frame. */
	void growToContain(double x0, double x1, double y0, double y1);
	/** Insert one keyframe's rays (camera frame) at a pose: classify, trace, update. */
	void integrateRays(
		const mrpt::poses::CPose3D& T_world_cam,
		const std::vector<mrpt::math::TPoint3Df>& points_cam);
	/** Depth image -> one representative point per endpoint cell (camera frame). */
	std::vector<mrpt::math::TPoint3Df> reduceDepth(
		const mrpt::poses::CPose3D& T_world_cam,
		const mrpt::obs::CObservation3DRangeScan& obs) const;
	bool ensureFloorFromDepth(
		const mrpt::poses::CPose3D& T_world_cam, const mrpt::obs::CObservation3DRangeScan& obs);

   public:
	MAP_DEFINITION_START(CISMOccupancyGrid2D)
	TCreationOptions creationOpts;
	TInsertionOptions insertionOpts;
	TLikelihoodOptions likelihoodOpts;
	/** The INI section prefix the options were read from */
	std::string optionSection;
	MAP_DEFINITION_END(CISMOccupancyGrid2D)
};

/** Depth pixels of an observation as points in the optical camera frame (depth camera
 * intrinsics, distortion ignored), every `decimation`-th row and column, invalid skipped. */
std::vector<mrpt::math::TPoint3Df> depthToCameraPoints(
	const mrpt::obs::CObservation3DRangeScan& obs, int decimation);

}  // namespace keygrid

#pragma once
/** \file CHOCPointsMap.h
 * keygrid::CHOCPointsMap — the SfM landmarks as an MRPT metric map: 3D points with their
 * feature descriptor and Histogram of Oriented Cameras (source paper 2; bins and update rule in
 * HocGeometry.h / HocHistogram.h). INI name `hocPointsMap`.
 *
 * Two ways to fill it:
 *  - keygrid-slam copies the frontend's landmarks (position, descriptor, histogram) into it
 *    (setPoints / upsertPoint): the frontend decides what is seen and matched;
 *  - insertObservation(CObservation3DRangeScan) on its own, e.g. from observations2map: every
 *    stored point that projects into the depth image inside the visible depth range is
 *    compared with the measured depth: the surface is where the point is (|d - z| <= tol) ->
 *    +1 in the camera's bin; the measured surface is behind the point (d > z + tol: the point
 *    is gone) or there is no reading (an occluder would have been measured) -> -1; a closer
 *    surface (d < z - tol) occludes it -> no update. Then decimated
 *    pixels whose voxel (insertion `point_spacing`) holds no point yet become new points (+1),
 *    and points whose largest bin weight is below prune_threshold are removed.
 *    tol = occlusion_tolerance_abs + occlusion_tolerance_rel * z.
 *
 * In a SLAM run (maps::KeyFrameMap, CHOCPointsMap_keyframes.cpp) the map follows the
 * frontend's landmarks (syncLandmarks) and takes nothing from keyframes or corrections itself.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/maps/DepthScanMap.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/HocGeometry.h>
#include <keygrid/maps/HocHistogram.h>
#include <keygrid/maps/KeyFrameMap.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace keygrid
{
class CHOCPointsMap : public maps::DepthScanMap, public maps::KeyFrameMap
{
	DEFINE_SERIALIZABLE(CHOCPointsMap, keygrid)

   public:
	struct Point
	{
		std::uint64_t id{0};
		mrpt::math::TPoint3D p;
		/** Feature descriptor bytes (ORB: 32 bytes; SIFT: 128 floats); may be empty. */
		std::vector<std::uint8_t> descriptor;
		maps::HocHistogram hoc;
	};

	/** insertObservation() of depth scans. INI section `_insertOpts`. */
	struct TInsertionOptions : public core::FieldTableOptions<TInsertionOptions>
	{
		/** Use every n-th pixel in rows and columns (Default: 8) */
		int decimation{8};
		/** A new point is created only in a voxel of this size without points [m] (Default: 0.05) */
		double pointSpacing{0.05};
		/** Prune after each inserted observation (Default: true) */
		bool prune{true};

		/** Its keys (OptionFields.h). */
		core::OptionFields fields();
	};

	/** Likelihood of a depth scan: product over decimated pixels of a Gaussian of the distance
	 * to the nearest map point (searched in the 27 neighbouring spacing-voxels), floored.
	 * INI section `_likelihoodOpts`. */
	struct TLikelihoodOptions : public core::FieldTableOptions<TLikelihoodOptions>
	{
		int decimation{16};  //!< (Default: 16)
		double sigma{0.05};  //!< [m] (Default: 0.05)
		double outlierProbability{0.05};  //!< floor of a pixel's likelihood (Default: 0.05)

		/** Its keys (OptionFields.h). */
		core::OptionFields fields();
	};

	/** Visualization: points coloured by their largest bin weight (red 0 .. green 1) and,
	 * optionally, icosahedron glyphs of the most observed points. */
	struct TRenderOptions
	{
		float pointSize{3.f};
		/** Number of glyphs (0: none) (Default: 0) */
		int glyphs{0};
		/** Glyph radius [m] (Default: 0.05) */
		double glyphRadius{0.05};
	};

	/** Descriptor geometry, weights and thresholds (INI section `_creationOpts`). */
	maps::HocOptions hocOptions;
	TInsertionOptions insertionOptions;
	TLikelihoodOptions likelihoodOptions;
	TRenderOptions renderOptions;

	CHOCPointsMap() = default;
	explicit CHOCPointsMap(const maps::HocOptions& opts) : hocOptions(opts) {}

	std::size_t size() const { return m_points.size(); }
	/** CMetricMap: no points. */
	bool isEmpty() const override { return m_points.empty(); }
	/** Points and bin geometry in one line. */
	std::string asString() const override;
	const std::vector<Point>& points() const { return m_points; }
	/** Replaces all points. Throws std::invalid_argument if a histogram has the wrong size. */
	void setPoints(std::vector<Point> pts);
	/** Largest bin weight of point i. */
	double maxWeight(std::size_t i) const { return hocOptions.weight(m_points.at(i).hoc.maxCount()); }
	/** Bin geometry for the current hocOptions. */
	const maps::HocGeometry& geometry() const;

	/** Removes points whose largest bin weight is below hocOptions.pruneThreshold; returns how
	 * many. */
	std::size_t prune();

	/** ASCII PLY: x y z, colour by weight, property `weight` (largest bin weight) and
	 * `observations` (sum of positive counts). Throws std::runtime_error if not writable.
	 * Points are mapped into `frame` (e.g. the floor frame); frame.comment is a PLY comment. */
	void saveAsPly(const std::string& path, const maps::ExportFrame& frame = {}) const;
	/** CMetricMap: writes `<prefix>.ply` (saveAsPly). */
	void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
	/** Visualizable: the points coloured by weight and the glyphs of TRenderOptions. */
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const override;

	/** @name In a SLAM run (maps::KeyFrameMap)
	 * @{ */
	/** The frontend decides what a keyframe adds: its landmarks come with syncLandmarks(). */
	void insertKeyFrame(const maps::MapKeyFrame&, const maps::KeyFrameFeed&) override {}
	/** Becomes `landmarks()` (points and hocOptions, the frontend's descriptor options, so the
	 * histograms keep their meaning), keeping its own insertion, likelihood and render
	 * options. */
	void syncLandmarks(const maps::LandmarkSource& landmarks) override;
	/** The landmarks are corrected by the frontend and come back with syncLandmarks().
	 * Returns false. */
	bool applyCorrection(const maps::MapCorrection&) override { return false; }
	/** The map has no mapping mode a loop closure would change. */
	void notifyLoopClosure() override {}
	/** The points stay in the SLAM world; the PLY export takes the frame it is written in. */
	void setFloorFrame(const std::optional<mrpt::poses::CPose3D>&) override {}
	/** hoc_points<suffix>.ply (saveAsPly, in out.frame()) and .bin (this map serialized,
	 * gz-compressed, in the SLAM world). */
	void writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const override;
	/** "points". */
	std::string summaryJsonFields() const override;
	/** @} */

   protected:
	void internal_clear() override;
	// maps::DepthScanMap
	bool insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) override;
	/** Any depth scan, once the map has points. */
	bool canComputeDepthScanLikelihood(const mrpt::obs::CObservation3DRangeScan&) const override { return !m_points.empty(); }
	double depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const override;

   private:
	std::vector<Point> m_points;
	std::uint64_t m_nextId{0};
	/** Cached geometry (rebuilt when the options change; a copy of the map starts empty). */
	struct GeometryCache
	{
		GeometryCache() = default;
		GeometryCache(const GeometryCache&) {}
		GeometryCache& operator=(const GeometryCache&)
		{
			ptr.reset();
			return *this;
		}
		mutable std::shared_ptr<maps::HocGeometry> ptr;
	};
	GeometryCache m_geometry;

	MAP_DEFINITION_START(CHOCPointsMap)
	keygrid::maps::HocOptions hocOpts;
	keygrid::CHOCPointsMap::TInsertionOptions insertionOpts;
	keygrid::CHOCPointsMap::TLikelihoodOptions likelihoodOpts;
	MAP_DEFINITION_END(CHOCPointsMap)
};

}  // namespace keygrid

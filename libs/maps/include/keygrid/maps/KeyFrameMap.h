#pragma once
/** \file KeyFrameMap.h
 * maps::KeyFrameMap — what a SLAM run asks of a map, beside MRPT's CMetricMap contract: take
 * keyframes, follow the frontend's landmarks, re-anchor on corrected keyframe poses, hear of
 * loop closures and of the run's floor frame, write its files. keygrid's three plugins
 * implement it (CISMOccupancyGrid2D, CSubmappedOccupancyGrid3D, CHOCPointsMap); any other
 * CMetricMap joins a run through ObservationFedMap. keygrid-slam's slam::MetricMaps holds the
 * maps of a run as a list of KeyFrameMap and hands every event to each of them.
 */
#include <keygrid/maps/GridMorphing.h>
#include <keygrid/maps/MapKeyFrame.h>
#include <keygrid/maps/MapOutputFolder.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace keygrid
{
class CHOCPointsMap;
}

namespace keygrid::maps
{
/** What a 2D navigation grid integrates of a keyframe (keygrid-slam's [maps] ism2d_input). */
enum class GridInput : uint8_t
{
	MapPoints = 0,  ///< its map points (the ISM paper's input)
	Depth = 1  ///< its depth image
};

/** The run's side of a keyframe insertion: its choices for the maps, and its keyframes. */
struct KeyFrameFeed
{
	/** What 2D grids integrate (Default: map points) */
	GridInput gridInput{GridInput::MapPoints};
	/** An earlier keyframe as it is now (pose after local bundle adjustment and loop
	 * closures), nullopt once it left the map: for a map that keeps a keyframe aside until it
	 * can integrate it. */
	std::function<std::optional<MapKeyFrame>(uint64_t id)> keyFrame;
};

/** A trajectory correction (loop closure, final refinement) as the maps take it. */
struct MapCorrection
{
	/** The keyframes that moved: the pose each was inserted with (or last corrected to), its
	 * corrected pose and the factor its camera-frame content grows by (PoseCorrection::scale:
	 * a monocular Sim(3) loop correction; 1 otherwise). */
	TrajectoryCorrection poses;
	/** The run's floor frame under the corrected poses (given, or the newest estimate);
	 * nullopt while none is known. */
	std::optional<mrpt::poses::CPose3D> T_world_floor;
	/** The world was scaled by this factor about its origin (x -> scale x) before the poses
	 * moved to their corrected values: a monocular map given metric scale. What a map holds in
	 * a keyframe's camera frame (map points, rays) scales by it (and then by the keyframe's own
	 * poses[id].scale), and so does the translation of every keyframe pose the correction does
	 * not name. 1 for a loop closure or a refinement. */
	double scale{1.0};
	/** Keyframes whose map points the run re-estimated (a map without depth after its final
	 * bundle adjustment): each one's points as the map holds them now, in the world after the
	 * correction. A map that keeps points per keyframe replaces that keyframe's with them; the
	 * others keep what they hold (moved with the pose). Empty for any other correction. */
	std::map<uint64_t, std::vector<mrpt::math::TPoint3D>> points_world;
};

/** The frontend's landmarks (positions, descriptors, Histograms of Oriented Cameras) as a HOC
 * points map, built when called: only maps that hold landmarks call it. */
using LandmarkSource = std::function<CHOCPointsMap()>;

class KeyFrameMap
{
   public:
	virtual ~KeyFrameMap() = default;

	/** Integrates keyframe `kf` (or keeps it aside until the map can, see KeyFrameFeed). */
	virtual void insertKeyFrame(const MapKeyFrame& kf, const KeyFrameFeed& feed) = 0;
	/** The frontend's landmarks changed (new keyframe, refinement): a map made of them takes
	 * them as they are now. */
	virtual void syncLandmarks(const LandmarkSource& landmarks) = 0;
	/** Re-anchors what the map holds on corrected keyframe poses. Returns false when the map
	 * had nothing to re-anchor (no re-anchoring, no time to report). */
	virtual bool applyCorrection(const MapCorrection& correction) = 0;
	/** A loop closed: the camera is back in mapped space. */
	virtual void notifyLoopClosure() = 0;
	/** The run's floor frame (z up, z = 0 on the floor), given or estimated: called once before
	 * the first keyframe (nullopt: the run estimates one, not known yet) and whenever an
	 * estimate moves it between keyframes; a map kept in that frame re-expresses what it holds.
	 * Throws std::invalid_argument when the map's own options set a floor the run's would
	 * silently replace. */
	virtual void setFloorFrame(const std::optional<mrpt::poses::CPose3D>& T_world_floor) = 0;
	/** Writes the map's files into `out`; `suffix` tells the n-th map of a class ("", "_1",
	 * ...) apart. Files that fail are recorded in `out`, the others still written. */
	virtual void writeOutputs(MapOutputFolder& out, const std::string& suffix) const = 0;
	/** JSON members describing the map's size (`"cells": 40000, ...`), for a run's report;
	 * empty when there is nothing to say beyond its class. */
	virtual std::string summaryJsonFields() const = 0;
};

}  // namespace keygrid::maps

#pragma once
/** \file ObservationFedMap.h
 * maps::ObservationFedMap — any CMetricMap that is not one of keygrid's (MRPT's own octoMap,
 * occupancyGrid, pointsMap, ...) as a KeyFrameMap: it takes a keyframe's depth as a
 * CObservation3DRangeScan at the keyframe's pose, cannot be re-anchored (it keeps the poses
 * it was given) and writes MRPT's own representation of itself.
 */
#include <keygrid/maps/KeyFrameMap.h>
#include <mrpt/maps/CMetricMap.h>

namespace keygrid::maps
{
class ObservationFedMap : public KeyFrameMap
{
   public:
	/** `map` is not owned and must outlive this. */
	explicit ObservationFedMap(mrpt::maps::CMetricMap& map) : m_map(map) {}

	/** insertObservation(kf.depthScan()) at the depth sensor's pose; nothing without depth. */
	void insertKeyFrame(const MapKeyFrame& kf, const KeyFrameFeed& feed) override;
	/** MRPT's maps hold no landmarks of the frontend. */
	void syncLandmarks(const LandmarkSource&) override {}
	/** MRPT's maps cannot be re-anchored: they keep the online poses. Returns false. */
	bool applyCorrection(const MapCorrection&) override { return false; }
	/** MRPT's maps have no mapping mode a loop closure would change. */
	void notifyLoopClosure() override {}
	/** MRPT's maps stay in the SLAM world. */
	void setFloorFrame(const std::optional<mrpt::poses::CPose3D>&) override {}
	/** saveMetricMapRepresentationToFile() with prefix `<class>` + suffix (':' -> '_'), e.g.
	 * octoMap's .bt: written into a scratch folder, then renamed into place, so each file
	 * appears whole. Recorded in `out` as `<prefix>.*`. */
	void writeOutputs(MapOutputFolder& out, const std::string& suffix) const override;
	/** Nothing beyond the class. */
	std::string summaryJsonFields() const override { return {}; }

   private:
	mrpt::maps::CMetricMap& m_map;
};

}  // namespace keygrid::maps

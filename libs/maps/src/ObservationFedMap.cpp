/** \file ObservationFedMap.cpp
 * ObservationFedMap: MRPT's own maps in a keygrid run.
 */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/ObservationFedMap.h>

#include <filesystem>

namespace keygrid::maps
{
void ObservationFedMap::insertKeyFrame(const MapKeyFrame& kf, const KeyFrameFeed&)
{
	if (kf.depth.empty()) return;
	m_map.insertObservation(kf.depthScan(), mrpt::poses::CPose3D(core::sensorPoseFromCameraPose(kf.T_world_cam)));
}

void ObservationFedMap::writeOutputs(MapOutputFolder& out, const std::string& suffix) const
{
	namespace fs = std::filesystem;
	std::string base = m_map.GetRuntimeClass()->className;
	for (auto& ch : base)
		if (ch == ':') ch = '_';
	out.write(base + suffix + ".*", [&](const std::string&) {
		const fs::path tmp = fs::path(out.dir()) / ".maps.tmp";
		fs::remove_all(tmp);
		fs::create_directories(tmp);
		m_map.saveMetricMapRepresentationToFile((tmp / (base + suffix)).string());
		for (const auto& e : fs::directory_iterator(tmp)) fs::rename(e.path(), fs::path(out.dir()) / e.path().filename());
		fs::remove_all(tmp);
	});
}

}  // namespace keygrid::maps

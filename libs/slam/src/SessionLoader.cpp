#include <keygrid/slam/SessionLoader.h>
#include <keygrid/store/SparseMapRecords.h>

#include <chrono>
#include <stdexcept>

namespace keygrid::slam
{
LoadedSession loadSparseMap(const store::SessionStore& session, sfm::SparseMap& map)
{
	if (map.numKeyFrames() || map.numLandmarks()) throw std::invalid_argument("loadSparseMap: the map must be empty");
	const auto t0 = std::chrono::steady_clock::now();
	LoadedSession out;
	try
	{
		for (const auto& rec : session.loadKeyFrames()) map.restoreKeyFrame(store::toKeyFrame(rec));
		// Each landmark points its observing keypoints at itself: the association comes from
		// the landmarks, the keyframes' stored association only has to agree with it.
		for (const auto& rec : session.loadLandmarks()) map.restoreLandmark(store::toLandmark(rec));
	}
	catch (const std::invalid_argument& e)
	{
		throw std::runtime_error("'" + session.path() + "': " + e.what());
	}
	for (const auto& e : session.loadCovisibility())
	{
		if (!map.hasKeyFrame(e.a) || !map.hasKeyFrame(e.b))
			throw std::runtime_error("'" + session.path() + "': covisibility edge " + std::to_string(e.a) + "-" +
									 std::to_string(e.b) + " names a keyframe that is not stored");
		map.keyframe(e.a).covisibility[e.b] = e.weight;
		map.keyframe(e.b).covisibility[e.a] = e.weight;
		out.covisibilityEdges++;
	}
	out.keyframes = map.numKeyFrames();
	out.landmarks = map.numLandmarks();
	out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	return out;
}

}  // namespace keygrid::slam

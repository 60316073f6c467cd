#include <keygrid/sfm/BundleWindow.h>

#include <stdexcept>
#include <string>

namespace keygrid::sfm
{
BundleWindow growBundleWindow(const SparseMap& map, const std::vector<KeyFrameId>& seeds, std::size_t maxKeyFrames)
{
	if (maxKeyFrames < 1) throw std::invalid_argument("growBundleWindow: maxKeyFrames = 0 (must be >= 1)");
	BundleWindow w;
	std::set<KeyFrameId> in;
	const auto add = [&](KeyFrameId id, std::vector<KeyFrameId>& ring)
	{
		if (w.local.size() >= maxKeyFrames || !map.hasKeyFrame(id) || !in.insert(id).second) return;
		w.local.push_back(id);
		ring.push_back(id);
	};
	std::vector<KeyFrameId> ring;
	for (KeyFrameId s : seeds) add(s, ring);
	while (!ring.empty() && w.local.size() < maxKeyFrames)
	{
		std::vector<KeyFrameId> next;
		for (KeyFrameId id : ring)
		{
			const auto& covis = map.keyframe(id).covisibility;
			for (KeyFrameId n : map.bestCovisibles(id, covis.size())) add(n, next);
		}
		ring = std::move(next);
	}
	for (KeyFrameId id : w.local)
		for (LandmarkId l : map.keyframe(id).landmarks)
			if (const Landmark* lm = l == kNoLandmark ? nullptr : map.findLandmark(l))
				for (const auto& [kf, kp] : lm->observations)
					if (!in.count(kf)) w.fixed.insert(kf);
	return w;
}

}  // namespace keygrid::sfm

#include <keygrid/store/SparseMapRecords.h>

#include <algorithm>

namespace keygrid::store
{
static_assert(kNoLandmark == sfm::kNoLandmark, "the store writes sfm's landmark ids unchanged");

KeyFrameRecord toRecord(const sfm::KeyFrame& kf, const loop::BowVector& bow)
{
	KeyFrameRecord r;
	r.id = kf.id;
	r.frameIndex = kf.frameIndex;
	r.timestamp = kf.timestamp;
	r.T_world_cam = kf.T_world_cam;
	r.parent = kf.parent;
	r.hasParent = kf.hasParent;
	r.camera = kf.features.camera;
	r.keypoints = kf.features.keypoints;
	r.undistorted = kf.features.undistorted;
	r.keypointDepth = kf.features.depth;
	r.descriptors = kf.features.descriptors;
	r.levelScale = kf.features.levelScale;
	r.numLevels = kf.features.numLevels;
	r.landmarks = kf.landmarks;
	r.bow = bow;
	return r;
}

sfm::KeyFrame toKeyFrame(const KeyFrameRecord& rec)
{
	sfm::KeyFrame kf;
	kf.id = rec.id;
	kf.frameIndex = static_cast<std::size_t>(rec.frameIndex);
	kf.timestamp = rec.timestamp;
	kf.T_world_cam = rec.T_world_cam;
	kf.parent = rec.parent;
	kf.hasParent = rec.hasParent;
	kf.features.camera = rec.camera;
	kf.features.keypoints = rec.keypoints;
	kf.features.undistorted = rec.undistorted;
	kf.features.depth = rec.keypointDepth;
	kf.features.descriptors = rec.descriptors;
	kf.features.levelScale = rec.levelScale;
	kf.features.numLevels = rec.numLevels;
	kf.features.buildGrid();
	kf.landmarks = rec.landmarks;
	return kf;
}

EncodedImages encodeImages(const sfm::KeyFrame& kf, const KeyFrameImageCodec& codec)
{
	return codec.encode(kf.colour, KeyFrameImageCodec::depthToRaw(kf.depth, kf.features.camera.depthUnits));
}

LandmarkRecord toRecord(const sfm::Landmark& lm)
{
	LandmarkRecord r;
	r.id = lm.id;
	r.p_world = lm.p_world;
	r.descriptor = lm.descriptor;
	r.observations = lm.observations;
	r.normal = lm.normal;
	r.minDistance = lm.minDistance;
	r.maxDistance = lm.maxDistance;
	r.firstKeyFrame = lm.firstKeyFrame;
	r.visibleCount = lm.visibleCount;
	r.foundCount = lm.foundCount;
	r.hocCounts = lm.hoc.counts();
	return r;
}

sfm::Landmark toLandmark(const LandmarkRecord& rec)
{
	sfm::Landmark lm;
	lm.id = rec.id;
	lm.p_world = rec.p_world;
	lm.descriptor = rec.descriptor;
	lm.observations = rec.observations;
	lm.normal = rec.normal;
	lm.minDistance = rec.minDistance;
	lm.maxDistance = rec.maxDistance;
	lm.firstKeyFrame = rec.firstKeyFrame;
	lm.visibleCount = rec.visibleCount;
	lm.foundCount = rec.foundCount;
	lm.hoc.setCounts(rec.hocCounts);
	return lm;
}

std::vector<CovisibilityEdge> covisibilityOf(const sfm::KeyFrame& kf)
{
	std::vector<CovisibilityEdge> out;
	out.reserve(kf.covisibility.size());
	for (const auto& [other, w] : kf.covisibility)
		if (other != kf.id) out.push_back({std::min(kf.id, other), std::max(kf.id, other), w});
	return out;
}

}  // namespace keygrid::store

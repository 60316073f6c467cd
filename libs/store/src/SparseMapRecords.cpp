#include <keygrid/store/SparseMapRecords.h>

#include <algorithm>

namespace keygrid::store
{
static_assert(kNoLandmark == sfm::kNoLandmark, "the store writes sfm's landmark ids unchanged");

namespace
{
/** Calls copy(kfField, recField) for every field a keyframe and its record both hold as it is,
 * in the order sfm::KeyFrame declares them. One side is const: the direction of the copy. */
template <class KeyFrame, class Record, class Copy>
void forKeyFrameFields(KeyFrame& kf, Record& rec, Copy&& copy)
{
	copy(kf.id, rec.id);
	copy(kf.frameIndex, rec.frameIndex);
	copy(kf.timestamp, rec.timestamp);
	copy(kf.T_world_cam, rec.T_world_cam);
	copy(kf.features.camera, rec.camera);
	copy(kf.features.keypoints, rec.keypoints);
	copy(kf.features.undistorted, rec.undistorted);
	copy(kf.features.depth, rec.keypointDepth);
	copy(kf.features.descriptors, rec.descriptors);
	copy(kf.features.levelScale, rec.levelScale);
	copy(kf.features.numLevels, rec.numLevels);
	copy(kf.landmarks, rec.landmarks);
	copy(kf.parent, rec.parent);
	copy(kf.hasParent, rec.hasParent);
}

/** copy() of the forKeyFrameFields table from the frontend's object into the record ... */
const auto intoRecord = [](const auto& object, auto& record) { record = object; };
/** ... and from the record into the object. */
const auto fromRecord = [](auto& object, const auto& record) { object = record; };
}  // namespace

KeyFrameRecord toRecord(const sfm::KeyFrame& kf, const loop::BowVector& bow)
{
	KeyFrameRecord r;
	forKeyFrameFields(kf, r, intoRecord);
	r.bow = bow;
	return r;
}

sfm::KeyFrame toKeyFrame(const KeyFrameRecord& rec)
{
	sfm::KeyFrame kf;
	forKeyFrameFields(kf, rec, fromRecord);
	kf.features.buildGrid();
	return kf;
}

EncodedImages encodeImages(const sfm::KeyFrame& kf, const KeyFrameImageCodec& codec)
{
	return codec.encode(kf.colour, KeyFrameImageCodec::depthToRaw(kf.depth, kf.features.camera.depthUnits));
}

LandmarkRecord toRecord(const sfm::Landmark& lm)
{
	LandmarkRecord r;
	static_cast<sfm::LandmarkState&>(r) = lm;
	r.hocCounts = lm.hoc.counts();
	return r;
}

sfm::Landmark toLandmark(const LandmarkRecord& rec)
{
	sfm::Landmark lm;
	static_cast<sfm::LandmarkState&>(lm) = rec;
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

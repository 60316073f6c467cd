#pragma once
/** \file SparseMapRecords.h
 * The frontend's keyframes and landmarks (keygrid::sfm) <-> the store's records. A keyframe's
 * covisibility lives in the store's covisibility table (CovisibilityEdge), not in its record.
 */
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionRecords.h>

namespace keygrid::store
{
/** The record of `kf` with its BoW vector (images are encoded separately, see encodeImages). */
KeyFrameRecord toRecord(const sfm::KeyFrame& kf, const loop::BowVector& bow);
/** A keyframe with the record's fields and its lookup grid built; no images, no covisibility. */
sfm::KeyFrame toKeyFrame(const KeyFrameRecord& rec);
/** Its colour image and its depth [m] converted to the camera's raw units, encoded. */
EncodedImages encodeImages(const sfm::KeyFrame& kf, const KeyFrameImageCodec& codec);

LandmarkRecord toRecord(const sfm::Landmark& lm);
sfm::Landmark toLandmark(const LandmarkRecord& rec);

/** The covisibility edges of `kf` towards other keyframes (a < b, weight = shared landmarks). */
std::vector<CovisibilityEdge> covisibilityOf(const sfm::KeyFrame& kf);

}  // namespace keygrid::store

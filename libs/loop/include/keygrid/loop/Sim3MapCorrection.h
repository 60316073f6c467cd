#pragma once
/** \file Sim3MapCorrection.h
 * Moving a sparse map by one similarity per keyframe, as a monocular map is corrected: its
 * keyframes keep rigid poses and their landmarks carry the scale (RigidCorrection). Used by the
 * Sim(3) loop correction and by slam::MetricScale's rescale of the newest stretch of path.
 */
#include <keygrid/loop/Sim3.h>
#include <keygrid/sfm/SparseMap.h>

#include <map>

namespace keygrid::loop
{
/** Every keyframe's pose as a similarity of unit scale: the map's units are the same everywhere
 * before a correction. */
std::map<sfm::KeyFrameId, Sim3> keyFrameSims(const sfm::SparseMap& map);

/** The keyframes of newS take the rigid part of their new similarity (camera centre and
 * orientation); every landmark follows its reference keyframe (the one that created it, else its
 * first observer) from oldS to newS, scale included (movePointWithKeyFrame). Keyframes missing
 * from newS stay where they are, and so do their landmarks. */
void applySim3Corrections(
	sfm::SparseMap& map, const std::map<sfm::KeyFrameId, Sim3>& oldS, const std::map<sfm::KeyFrameId, Sim3>& newS);

}  // namespace keygrid::loop

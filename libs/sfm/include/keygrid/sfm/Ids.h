#pragma once
/** \file Ids.h
 * Ids of the frontend's keyframes and landmarks (monotonic within a map), also the ids under
 * which a session store keeps them (store::KeyFrameRecord, store::LandmarkRecord).
 */
#include <cstdint>

namespace keygrid::sfm
{
using KeyFrameId = std::uint64_t;
using LandmarkId = std::uint64_t;
/** Landmark of a keypoint that has none. */
constexpr LandmarkId kNoLandmark = ~LandmarkId(0);

}  // namespace keygrid::sfm

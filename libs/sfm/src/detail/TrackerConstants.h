#pragma once
/** \file TrackerConstants.h
 * Constants shared by the Tracker's source files (Tracker.cpp, Tracker_monocular.cpp).
 */

namespace keygrid::sfm::detail
{
/** A keyframe needs more inliers than this (ORB-SLAM2's 15): a barely tracked frame would
 * bring a poor pose into the map. */
constexpr int kMinKeyFrameInliers = 15;
}  // namespace keygrid::sfm::detail

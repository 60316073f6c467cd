#pragma once
/** \file SessionLoader.h
 * A stored session (store::SessionStore) back into a sparse map: keyframes with their ids,
 * features and poses (no images: those stay in the file), landmarks with their observations
 * and HOC histograms, covisibility. Used by keygrid-slam --load-map.
 */
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/store/SessionStore.h>

namespace keygrid::slam
{
struct LoadedSession
{
	std::size_t keyframes{0}, landmarks{0}, covisibilityEdges{0};
	/** Time to read and rebuild [s] */
	double seconds{0};
};

/** Fills `map`, which must be empty (std::invalid_argument otherwise). Throws
 * std::runtime_error naming the file when a record refers to one that is not stored. */
LoadedSession loadSparseMap(const store::SessionStore& session, sfm::SparseMap& map);

}  // namespace keygrid::slam

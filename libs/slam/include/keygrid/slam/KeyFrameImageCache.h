#pragma once
/** \file KeyFrameImageCache.h
 * Keeps keyframe images out of RAM, so that a run's memory stays bounded. Once a keyframe has been
 * inserted into the metric maps and handed to the session recorder, System moves its images
 * here (put) and the keyframe drops them; whoever needs them later (dense 2D input waiting for
 * the floor, keyframes.simplemap) loads them through the cache.
 *
 * An LRU of at most `capacityBytes` keeps the most recently put or read images in RAM; images
 * leave RAM for an ImageSpillFile (raw bytes: bit-identical on the way back) when they are
 * evicted, or at once when they are larger than the whole cache. A run whose keyframe images
 * fit in the cache never writes the file.
 */
#include <keygrid/slam/ImageSpillFile.h>
#include <keygrid/slam/KeyFrameImageSource.h>

#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace keygrid::slam
{
class KeyFrameImageCache : public KeyFrameImageSource
{
   public:
	struct Stats
	{
		std::size_t hits{0}, misses{0}, evictions{0};
	};

	/** `capacityBytes`: images kept in RAM at most (0: none); `spillDir`: folder of the spill
	 * file (empty: $TMPDIR, else /tmp). */
	explicit KeyFrameImageCache(std::size_t capacityBytes, const std::string& spillDir = {});

	/** Stores the images of keyframe `id` (replacing any stored before). Thread-safe. Throws
	 * std::runtime_error when images leaving RAM cannot be written to the spill file. */
	void put(sfm::KeyFrameId id, const KeyFrameImageData& images);
	/** Whether images of `id` were put. */
	bool contains(sfm::KeyFrameId id) const;
	/** The images of `id`; throws std::out_of_range naming the id when none were put.
	 * Thread-safe. */
	KeyFrameImageData get(sfm::KeyFrameId id) const;

	/** The keyframe's own images when it still holds any, else the stored ones (none: empty). */
	bool hasImages(const sfm::KeyFrame& kf) const override;
	KeyFrameImageData load(const sfm::KeyFrame& kf) const override;

	std::size_t capacityBytes() const { return m_capacity; }
	/** Bytes of the images held in RAM now. */
	std::size_t cachedBytes() const;
	/** Keyframes whose images are held in RAM now. */
	std::size_t cachedCount() const;
	/** Bytes in the spill file. */
	std::uint64_t spilledBytes() const { return m_file.size(); }
	Stats stats() const;

   private:
	struct Stored
	{
		bool inFile{false};  //!< written to the spill file (else only in m_cached)
		bool hasDepth{false}, hasColour{false};
		ImageSpillFile::Record depth, colour;
	};
	struct Cached
	{
		KeyFrameImageData images;
		std::size_t bytes{0};
		std::list<sfm::KeyFrameId>::iterator lru;
	};
	/** Puts `images` first in the LRU and evicts from its end down to the capacity, writing
	 * evicted images that are not in the spill file yet. Lock held. */
	void remember(sfm::KeyFrameId id, const KeyFrameImageData& images) const;
	void forget(sfm::KeyFrameId id) const;
	/** Writes the images of `id` to the spill file unless they are there already. Lock held. */
	void spill(sfm::KeyFrameId id, const KeyFrameImageData& images) const;

	std::size_t m_capacity;
	mutable ImageSpillFile m_file;  // written on eviction, also from const get()
	mutable std::unordered_map<sfm::KeyFrameId, Stored> m_stored;
	mutable std::list<sfm::KeyFrameId> m_lru;  // most recent first
	mutable std::unordered_map<sfm::KeyFrameId, Cached> m_cached;
	mutable std::size_t m_cachedBytes{0};
	mutable Stats m_stats;
	mutable std::mutex m_mutex;
};

}  // namespace keygrid::slam

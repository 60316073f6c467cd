#pragma once
/** \file MapSnapshotCodec.h
 * A metric map <-> MapSnapshot: MRPT's own versioned serialization (archiveFrom << map),
 * gz-compressed, i.e. the bytes of the *.bin files slam::MetricMaps writes.
 */
#include <keygrid/store/SessionRecords.h>
#include <mrpt/serialization/CSerializable.h>

#include <string>

namespace keygrid::store
{
class MapSnapshotCodec
{
   public:
	/** Serializes `map` (any CSerializable, normally a CMetricMap) into a snapshot.
	 * gzLevel: zlib level 1 .. 9. Throws std::runtime_error when compression fails. */
	static MapSnapshot encode(
		const std::string& name, const mrpt::serialization::CSerializable& map, KeyFrameId lastKeyFrame, int gzLevel = 1);
	/** The object of a snapshot (cast it with std::dynamic_pointer_cast). Throws
	 * std::runtime_error naming the snapshot when the data does not decompress or deserialize
	 * (including an unknown class or serialization version). */
	static mrpt::serialization::CSerializable::Ptr decode(const MapSnapshot& snapshot);
	/** The gz data of a snapshot as it is written to a *.bin file. */
	static void saveAsFile(const MapSnapshot& snapshot, const std::string& path);
};

}  // namespace keygrid::store

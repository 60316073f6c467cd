#include <keygrid/core/AtomicOutput.h>
#include <keygrid/store/GzipBlock.h>
#include <keygrid/store/MapSnapshotCodec.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>

#include <fstream>
#include <stdexcept>

namespace keygrid::store
{
namespace
{
// A serialized map over 16 GiB is larger than any snapshot keygrid writes; the bound
// keeps a damaged length from claiming all memory.
constexpr std::size_t kMaxSnapshotBytes = std::size_t{16} << 30;
}  // namespace

MapSnapshot MapSnapshotCodec::encode(
	const std::string& name, const mrpt::serialization::CSerializable& map, KeyFrameId lastKeyFrame, int gzLevel)
{
	if (gzLevel < 1 || gzLevel > 9)
		throw std::invalid_argument("MapSnapshotCodec::encode: gzLevel must be in 1..9, got " + std::to_string(gzLevel));
	mrpt::io::CMemoryStream mem;
	mrpt::serialization::archiveFrom(mem) << map;
	const auto* p = static_cast<const std::uint8_t*>(mem.getRawBufferData());
	const std::vector<std::uint8_t> raw(p, p + mem.getTotalBytesCount());
	MapSnapshot s;
	s.name = name;
	s.lastKeyFrame = lastKeyFrame;
	s.data = gzipCompress(raw, gzLevel);
	return s;
}

mrpt::serialization::CSerializable::Ptr MapSnapshotCodec::decode(const MapSnapshot& snapshot)
{
	std::vector<std::uint8_t> raw;
	try
	{
		raw = gzipDecompress(snapshot.data, kMaxSnapshotBytes);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("map snapshot '" + snapshot.name + "': " + e.what());
	}
	mrpt::io::CMemoryStream mem;
	mem.assignMemoryNotOwn(raw.data(), raw.size());
	try
	{
		return mrpt::serialization::archiveFrom(mem).ReadObject();
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("map snapshot '" + snapshot.name + "' does not deserialize: " + e.what());
	}
}

void MapSnapshotCodec::saveAsFile(const MapSnapshot& snapshot, const std::string& path)
{
	core::writeFileAtomically(
		path, std::string(reinterpret_cast<const char*>(snapshot.data.data()), snapshot.data.size()));
}

}  // namespace keygrid::store

#include <keygrid/store/MapSnapshotCodec.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/io/zip.h>
#include <mrpt/serialization/CArchive.h>

#include <fstream>
#include <stdexcept>

namespace keygrid::store
{
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
	if (!mrpt::io::zip::compress_gz_data_block(raw, s.data, gzLevel))
		throw std::runtime_error("MapSnapshotCodec::encode: gz compression of snapshot '" + name + "' failed");
	return s;
}

mrpt::serialization::CSerializable::Ptr MapSnapshotCodec::decode(const MapSnapshot& snapshot)
{
	std::vector<std::uint8_t> raw;
	if (!mrpt::io::zip::decompress_gz_data_block(snapshot.data, raw))
		throw std::runtime_error("map snapshot '" + snapshot.name + "': the data is not gz-compressed");
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
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f.write(reinterpret_cast<const char*>(snapshot.data.data()), static_cast<std::streamsize>(snapshot.data.size()));
	if (!f) throw std::runtime_error("cannot write map snapshot '" + snapshot.name + "' to '" + path + "'");
}

}  // namespace keygrid::store

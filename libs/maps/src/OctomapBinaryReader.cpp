#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/OctomapBinaryReader.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
namespace
{
constexpr int kLevels = 16;
constexpr int32_t kKeyOffset = 32768;
constexpr int kFree = 1, kOccupied = 2, kInner = 3;

class TreeDecoder
{
   public:
	TreeDecoder(std::istream& in, const std::string& path, OctomapBinaryVoxels& out) : m_in(in), m_path(path), m_out(out) {}

	/** The node whose voxel keys start at `key` and span 2^level per axis: its two bytes, then
	 * its inner children depth-first (OcTree::readBinaryNode). */
	void node(const std::array<int32_t, 3>& key, int level)
	{
		char bytes[2];
		if (!m_in.read(bytes, 2)) throw std::runtime_error("'" + m_path + "': the tree data ends early");
		const int half = 1 << (level - 1);
		std::array<int, 8> code{};
		for (int c = 0; c < 8; c++) code[c] = (static_cast<unsigned char>(bytes[c / 4]) >> (2 * (c % 4))) & 3;
		for (int c = 0; c < 8; c++)
		{
			const std::array<int32_t, 3> child{key[0] + (c & 1 ? half : 0), key[1] + (c & 2 ? half : 0), key[2] + (c & 4 ? half : 0)};
			if (code[c] == kInner)
			{
				if (level == 1) throw std::runtime_error("'" + m_path + "': an inner node below the last level");
				node(child, level - 1);
			}
			else if (code[c] == kFree || code[c] == kOccupied)
				leaf(child, half, code[c] == kOccupied ? m_out.occupied : m_out.free);
		}
	}

   private:
	/** Every voxel of a leaf spanning `span` voxels per axis. */
	static void leaf(const std::array<int32_t, 3>& key, int span, std::vector<OctomapBinaryVoxels::Index>& to)
	{
		for (int z = 0; z < span; z++)
			for (int y = 0; y < span; y++)
				for (int x = 0; x < span; x++)
					to.push_back({key[0] + x - kKeyOffset, key[1] + y - kKeyOffset, key[2] + z - kKeyOffset});
	}

	std::istream& m_in;
	const std::string& m_path;
	OctomapBinaryVoxels& m_out;
};
}  // namespace

OctomapBinaryVoxels readOctomapBinary(const std::string& path)
{
	std::ifstream in(path, std::ios::binary);
	if (!in) throw std::runtime_error("cannot read '" + path + "'");
	OctomapBinaryVoxels out;
	std::string line, id;
	std::size_t size = 0;
	bool haveRes = false;
	if (!std::getline(in, line) || line.rfind("# Octomap OcTree binary file", 0) != 0)
		throw std::runtime_error("'" + path + "' is not an OctoMap binary file (first line '# Octomap OcTree binary file')");
	// Header (AbstractOcTree::readBinary): '#' comment lines and keywords up to "data".
	while (std::getline(in, line))
	{
		if (!line.empty() && line.back() == '\r') line.pop_back();
		if (line.empty()) continue;
		if (line[0] == '#')
		{
			const auto text = line.find_first_not_of("# ");
			if (text == std::string::npos) continue;
			out.comments.push_back(line.substr(text));
			if (auto T = floorFrameFromComment(line)) out.T_world_floor = T;
			continue;
		}
		std::istringstream is(line);
		std::string key;
		is >> key;
		if (key == "data") break;
		if (key == "id") is >> id;
		else if (key == "size") is >> size;
		else if (key == "res") haveRes = static_cast<bool>(is >> out.resolution);
	}
	if (line.rfind("data", 0) != 0) throw std::runtime_error("'" + path + "': the header has no 'data' line");
	if (id != "OcTree") throw std::runtime_error("'" + path + "': id '" + id + "' is not OcTree");
	if (!haveRes || !(out.resolution > 0)) throw std::runtime_error("'" + path + "': no positive 'res' in the header");
	if (size > 0)
	{
		TreeDecoder decoder(in, path, out);
		decoder.node({0, 0, 0}, kLevels);
	}
	return out;
}

}  // namespace keygrid::maps

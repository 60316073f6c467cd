#include <keygrid/maps/OctomapBinaryWriter.h>

#include <algorithm>
#include <array>

namespace keygrid::maps
{
namespace
{
constexpr int kLevels = 16;

/** Spreads the 16 bits of k to every third bit (bit b goes to bit 3b). */
uint64_t spreadBits(uint64_t k)
{
	k &= 0xffff;
	k = (k | (k << 16)) & 0x0000ff0000ffULL;
	k = (k | (k << 8)) & 0x00f00f00f00fULL;
	k = (k | (k << 4)) & 0x0c30c30c30c3ULL;
	k = (k | (k << 2)) & 0x249249249249ULL;
	return k;
}

constexpr int kFree = 1, kOccupied = 2, kInner = 3;
}  // namespace

bool OctomapBinaryWriter::add(int32_t x, int32_t y, int32_t z, bool occupied)
{
	const auto inRange = [](int32_t v) { return v >= -kKeyOffset && v < kKeyOffset; };
	if (!inRange(x) || !inRange(y) || !inRange(z)) return false;
	const auto key = [](int32_t v) { return static_cast<uint64_t>(v + kKeyOffset); };
	const uint64_t morton = spreadBits(key(x)) | (spreadBits(key(y)) << 1) | (spreadBits(key(z)) << 2);
	m_leaves.push_back((morton << 1) | (occupied ? 1u : 0u));
	return true;
}

std::string OctomapBinaryWriter::encodeTree(std::size_t& nodes)
{
	// Depth-first order; of a voxel added twice the last state stays (stable sort by key).
	std::stable_sort(m_leaves.begin(), m_leaves.end(), [](uint64_t a, uint64_t b) { return (a >> 1) < (b >> 1); });
	std::size_t kept = 0;
	for (std::size_t i = 0; i < m_leaves.size(); i++)
	{
		if (kept > 0 && (m_leaves[kept - 1] >> 1) == (m_leaves[i] >> 1))
			m_leaves[kept - 1] = m_leaves[i];
		else
			m_leaves[kept++] = m_leaves[i];
	}
	m_leaves.resize(kept);
	std::string out;
	nodes = 0;
	if (m_leaves.empty()) return out;  // no root: OctoMap writes no data
	nodes = 1;
	encodeNode(0, m_leaves.size(), kLevels, out, nodes);
	return out;
}

int OctomapBinaryWriter::encodeNode(std::size_t begin, std::size_t end, int level, std::string& out, std::size_t& nodes) const
{
	if (level == 0) return (m_leaves[begin] & 1u) ? kOccupied : kFree;
	// The node's two bytes come before its children's: reserved now, filled (or dropped when
	// the node collapses) once the children are known.
	const std::size_t at = out.size();
	out.append(2, '\0');
	const int shift = 1 + 3 * (level - 1);
	std::array<int, 8> code{};
	int present = 0;
	for (std::size_t i = begin; i < end;)
	{
		const int child = static_cast<int>((m_leaves[i] >> shift) & 7u);
		std::size_t j = i + 1;
		while (j < end && static_cast<int>((m_leaves[j] >> shift) & 7u) == child) j++;
		code[static_cast<std::size_t>(child)] = encodeNode(i, j, level - 1, out, nodes);
		present++;
		i = j;
	}
	// Pruning (never the root): eight leaves of one state make this node a leaf.
	if (level < kLevels && present == 8 && code[0] != kInner && std::all_of(code.begin(), code.end(), [&](int c) { return c == code[0]; }))
	{
		out.resize(at);
		return code[0];
	}
	nodes += static_cast<std::size_t>(present);
	unsigned char bytes[2] = {0, 0};
	for (int c = 0; c < 8; c++) bytes[c / 4] |= static_cast<unsigned char>(code[static_cast<std::size_t>(c)] << (2 * (c % 4)));
	out[at] = static_cast<char>(bytes[0]);
	out[at + 1] = static_cast<char>(bytes[1]);
	return kInner;
}

void OctomapBinaryWriter::write(std::ostream& out, double resolution, const std::string& comment)
{
	std::size_t nodes = 0;
	const std::string tree = encodeTree(nodes);
	// OctoMap's header (AbstractOcTree::writeBinary); its reader skips lines starting with '#'.
	out << "# Octomap OcTree binary file\n";
	if (!comment.empty()) out << "# " << comment << "\n";
	out << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
		<< "id OcTree\nsize " << nodes << "\nres " << resolution << "\ndata\n";
	out.write(tree.data(), static_cast<std::streamsize>(tree.size()));
}

}  // namespace keygrid::maps

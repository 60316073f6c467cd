#include <keygrid/core/AtomicOutput.h>
/** \file VocabularyIO.cpp
 * Binary file format of the vocabulary (all integers little-endian, as written by x86/ARM):
 *
 *   char[8]  magic "KGVOCAB\0"
 *   u32      version (Vocabulary::kFileVersion)
 *   u32      descriptor type (0 binary, 1 float), u32 columns, u32 k, u32 L
 *   u64      training images, u64 nodes, u64 words
 *   nodes x  { u32 firstChild, u32 numChildren, i32 word, i32 depth }
 *   nodes x  centre row (columns bytes or columns floats; row 0 = root, zeros)
 *   words x  f64 idf
 *   char[8]  end marker "KGVOCEND"
 */
#include <keygrid/loop/Vocabulary.h>

#include <cstring>
#include <fstream>
#include <stdexcept>

namespace keygrid::loop
{
namespace
{
constexpr char kMagic[8] = {'K', 'G', 'V', 'O', 'C', 'A', 'B', '\0'};
constexpr char kEnd[8] = {'K', 'G', 'V', 'O', 'C', 'E', 'N', 'D'};

template <typename T>
void put(std::ostream& os, T v)
{
	os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T get(std::istream& is, const char* what)
{
	T v{};
	if (!is.read(reinterpret_cast<char*>(&v), sizeof(T)))
		throw std::runtime_error(std::string("vocabulary file truncated (reading ") + what + ")");
	return v;
}
}  // namespace

void Vocabulary::save(std::ostream& os) const
{
	if (empty()) throw std::logic_error("Vocabulary::save: empty vocabulary");
	os.write(kMagic, sizeof(kMagic));
	put<std::uint32_t>(os, kFileVersion);
	put<std::uint32_t>(os, static_cast<std::uint32_t>(m_type));
	put<std::uint32_t>(os, static_cast<std::uint32_t>(m_cols));
	put<std::uint32_t>(os, static_cast<std::uint32_t>(m_branching));
	put<std::uint32_t>(os, static_cast<std::uint32_t>(m_levels));
	put<std::uint64_t>(os, m_trainingImages);
	put<std::uint64_t>(os, m_nodes.size());
	put<std::uint64_t>(os, m_words.size());
	for (const auto& n : m_nodes)
	{
		put(os, n.firstChild);
		put(os, n.numChildren);
		put(os, n.word);
		put(os, n.depth);
	}
	const std::size_t rowBytes = m_centres.cols * m_centres.elemSize();
	for (int r = 0; r < m_centres.rows; ++r) os.write(reinterpret_cast<const char*>(m_centres.ptr(r)), static_cast<std::streamsize>(rowBytes));
	for (double w : m_idf) put(os, w);
	os.write(kEnd, sizeof(kEnd));
	if (!os) throw std::runtime_error("Vocabulary::save: write failed");
}

void Vocabulary::save(const std::string& path) const
{
	core::writeFileAtomically(path, [&](std::ostream& f) { save(f); });
}

Vocabulary Vocabulary::load(std::istream& is)
{
	char magic[8];
	if (!is.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(magic)) != 0)
		throw std::runtime_error("not a keygrid vocabulary file (bad magic)");
	const auto version = get<std::uint32_t>(is, "version");
	if (version != kFileVersion)
		throw std::runtime_error(
			"unknown vocabulary file version " + std::to_string(version) + " (this build reads " +
			std::to_string(kFileVersion) + ")");
	Vocabulary v;
	const auto type = get<std::uint32_t>(is, "type");
	if (type > 1) throw std::runtime_error("vocabulary file: unknown descriptor type " + std::to_string(type));
	v.m_type = static_cast<DescriptorType>(type);
	v.m_cols = static_cast<int>(get<std::uint32_t>(is, "columns"));
	v.m_branching = static_cast<int>(get<std::uint32_t>(is, "k"));
	v.m_levels = static_cast<int>(get<std::uint32_t>(is, "L"));
	v.m_trainingImages = get<std::uint64_t>(is, "training images");
	const auto nodes = get<std::uint64_t>(is, "node count");
	const auto words = get<std::uint64_t>(is, "word count");
	if (v.m_cols <= 0 || v.m_cols > 4096 || nodes < 2 || nodes > (1ULL << 26) || words == 0 || words >= nodes)
		throw std::runtime_error("vocabulary file: inconsistent header");
	v.m_nodes.resize(nodes);
	v.m_words.assign(words, 0);
	std::vector<char> wordSeen(words, 0);
	for (std::size_t i = 0; i < nodes; ++i)
	{
		Node& n = v.m_nodes[i];
		n.firstChild = get<std::uint32_t>(is, "nodes");
		n.numChildren = get<std::uint32_t>(is, "nodes");
		n.word = get<std::int32_t>(is, "nodes");
		n.depth = get<std::int32_t>(is, "nodes");
		const bool childrenOk = n.numChildren == 0 || (n.firstChild > i && static_cast<std::uint64_t>(n.firstChild) + n.numChildren <= nodes);
		const bool wordOk = n.numChildren > 0 ? n.word == -1 : (n.word >= 0 && static_cast<std::uint64_t>(n.word) < words);
		if (!childrenOk || !wordOk || (i > 0 && n.numChildren == 0 && wordSeen[static_cast<std::size_t>(n.word)]))
			throw std::runtime_error("vocabulary file: inconsistent node " + std::to_string(i));
		if (n.numChildren == 0 && i > 0)
		{
			wordSeen[static_cast<std::size_t>(n.word)] = 1;
			v.m_words[static_cast<std::size_t>(n.word)] = static_cast<NodeId>(i);
		}
	}
	if (v.m_nodes[0].numChildren == 0) throw std::runtime_error("vocabulary file: root without children");
	for (char s : wordSeen)
		if (!s) throw std::runtime_error("vocabulary file: a word has no leaf");
	v.m_centres.create(static_cast<int>(nodes), v.m_cols, v.m_type == DescriptorType::Binary ? CV_8U : CV_32F);
	const std::size_t rowBytes = v.m_centres.cols * v.m_centres.elemSize();
	for (int r = 0; r < v.m_centres.rows; ++r)
		if (!is.read(reinterpret_cast<char*>(v.m_centres.ptr(r)), static_cast<std::streamsize>(rowBytes)))
			throw std::runtime_error("vocabulary file truncated (reading centres)");
	v.m_idf.resize(words);
	for (auto& w : v.m_idf) w = get<double>(is, "idf weights");
	char end[8];
	if (!is.read(end, sizeof(end)) || std::memcmp(end, kEnd, sizeof(end)) != 0)
		throw std::runtime_error("vocabulary file truncated (missing end marker)");
	return v;
}

Vocabulary Vocabulary::load(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("cannot open vocabulary file " + path);
	try
	{
		return load(f);
	}
	catch (const std::runtime_error& e)
	{
		throw std::runtime_error(path + ": " + e.what());
	}
}

}  // namespace keygrid::loop

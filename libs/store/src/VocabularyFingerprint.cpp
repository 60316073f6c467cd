#include <keygrid/store/VocabularyFingerprint.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace keygrid::store
{
std::string fnv1a64Hex(const void* bytes, std::size_t n)
{
	std::uint64_t h = 14695981039346656037ull;
	const auto* p = static_cast<const std::uint8_t*>(bytes);
	for (std::size_t i = 0; i < n; i++)
	{
		h ^= p[i];
		h *= 1099511628211ull;
	}
	char buf[17];
	std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
	return buf;
}

VocabularyIdentity vocabularyIdentity(const loop::Vocabulary& vocabulary, const std::string& fileName)
{
	std::ostringstream os(std::ios::binary);
	vocabulary.save(os);
	const std::string bytes = os.str();
	return {std::filesystem::path(fileName).filename().string(), fnv1a64Hex(bytes.data(), bytes.size()), vocabulary.numWords()};
}

VocabularyIdentity vocabularyIdentityOfFile(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("cannot read vocabulary '" + path + "'");
	const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	std::istringstream is(bytes, std::ios::binary);
	loop::Vocabulary v;
	try
	{
		v = loop::Vocabulary::load(is);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("'" + path + "' is not a vocabulary: " + e.what());
	}
	return {std::filesystem::path(path).filename().string(), fnv1a64Hex(bytes.data(), bytes.size()), v.numWords()};
}

}  // namespace keygrid::store

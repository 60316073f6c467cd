/** \file SessionStore_vocabulary.cpp
 * The vocabulary's identity in `meta` and, optionally, the vocabulary itself in `vocabulary`.
 */
#include <keygrid/store/SessionStore.h>
#include <keygrid/store/VocabularyFingerprint.h>

#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "SessionStoreImpl.h"

namespace keygrid::store
{
void SessionStore::setVocabulary(const VocabularyIdentity& vocabulary)
{
	if (m_impl->mode != Mode::ReadWrite)
		throw std::logic_error("SessionStore::setVocabulary: '" + path() + "' was opened read-only");
	const VocabularyIdentity before = m_impl->meta.vocabulary;
	m_impl->meta.vocabulary = vocabulary;
	try
	{
		detail::SqliteTransaction tx(m_impl->db);
		m_impl->writeMeta();
		tx.commit();
	}
	catch (...)
	{
		m_impl->meta.vocabulary = before;
		throw;
	}
}

void SessionStore::storeVocabulary(const loop::Vocabulary& vocabulary, const std::string& name)
{
	if (m_impl->mode != Mode::ReadWrite)
		throw std::logic_error("SessionStore::storeVocabulary: '" + path() + "' was opened read-only");
	std::ostringstream os(std::ios::binary);
	vocabulary.save(os);
	const std::string bytes = os.str();
	const VocabularyIdentity before = m_impl->meta.vocabulary;
	m_impl->meta.vocabulary = {std::filesystem::path(name).filename().string(), fnv1a64Hex(bytes.data(), bytes.size()),
							   vocabulary.numWords()};
	try
	{
		detail::SqliteTransaction tx(m_impl->db);
		m_impl->writeMeta();
		auto& st = m_impl->statement("INSERT OR REPLACE INTO vocabulary(id, data) VALUES(1, ?1)");
		st.bindBlob(1, bytes.data(), bytes.size());
		st.run();
		tx.commit();
	}
	catch (...)
	{
		m_impl->meta.vocabulary = before;
		throw;
	}
}

bool SessionStore::hasStoredVocabulary() const
{
	return m_impl->db.queryInt("SELECT count(*) FROM vocabulary") > 0;
}

std::optional<loop::Vocabulary> SessionStore::loadVocabulary() const
{
	auto& st = m_impl->statement("SELECT data FROM vocabulary WHERE id = 1");
	if (!st.step())
	{
		st.reset();
		return std::nullopt;
	}
	std::size_t n = 0;
	const auto* p = st.blob(0, n);
	const std::string bytes(reinterpret_cast<const char*>(p), n);
	st.reset();
	const std::string hash = fnv1a64Hex(bytes.data(), bytes.size());
	if (hash != m_impl->meta.vocabulary.hash)
		throw std::runtime_error("'" + path() + "' is damaged: the stored vocabulary hashes to " + hash + ", meta says " +
								 m_impl->meta.vocabulary.hash);
	std::istringstream is(bytes, std::ios::binary);
	try
	{
		return loop::Vocabulary::load(is);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("'" + path() + "': the stored vocabulary does not load: " + e.what());
	}
}

}  // namespace keygrid::store

#pragma once
/** \file VocabularyFingerprint.h
 * The VocabularyIdentity of a vocabulary: its file name and a hash of its serialized bytes, so a
 * vocabulary loaded from a file and the same one trained in-run and saved get the same hash.
 */
#include <keygrid/loop/Vocabulary.h>
#include <keygrid/store/SessionRecords.h>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::store
{
/** FNV-1a 64-bit hash of `bytes` as 16 lower-case hex digits. */
std::string fnv1a64Hex(const void* bytes, std::size_t n);

/** Identity of `vocabulary` (hash of Vocabulary::save's bytes); `fileName` is stored without
 * its directory. */
VocabularyIdentity vocabularyIdentity(const loop::Vocabulary& vocabulary, const std::string& fileName);

/** Identity of a vocabulary file (hash of the file's bytes, words from loading it). Throws
 * std::runtime_error naming the file when it cannot be read or is not a vocabulary. */
VocabularyIdentity vocabularyIdentityOfFile(const std::string& path);

}  // namespace keygrid::store

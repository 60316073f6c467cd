#pragma once
/** \file AtomicFile.h
 * Output files appear whole or not at all: written to `<path>.tmp`, then renamed.
 */
#include <string>

namespace keygrid::slam
{
/** Writes `content` to `path` atomically. Throws std::runtime_error naming the path on failure. */
void writeFileAtomically(const std::string& path, const std::string& content);

}  // namespace keygrid::slam

#pragma once
/** \file DataFiles.h
 * Run-time data shipped with keygrid (share/ in the source tree, <prefix>/share/keygrid once
 * installed), e.g. the default vocabulary.
 */
#include <string>
#include <vector>

namespace keygrid::loop
{
/** Folders searched, in order: $KEYGRID_SHARE_DIR (when set), share/keygrid beside the running
 * executable's folder (an installed tool, in whatever prefix), the source tree's share/, the
 * configured install prefix's <datadir>/keygrid. */
std::vector<std::string> dataDirectories();

/** Full path of `relative` (e.g. "vocabulary/keygrid_orb_k10_L4.bin") in the first folder of
 * dataDirectories() holding it; throws std::runtime_error naming every folder searched. */
std::string findDataFile(const std::string& relative);

}  // namespace keygrid::loop

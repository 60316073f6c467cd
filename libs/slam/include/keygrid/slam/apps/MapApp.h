#pragma once
/** \file MapApp.h
 * keygrid-map: inspects session files (keygrid::store::SessionStore, doc/session-store.md).
 * `info FILE` prints the meta table, row counts and sizes; `check FILE` runs the version and
 * integrity checks and reads every record (exit 1 with a one-line reason when one fails).
 */
namespace keygrid::slam
{
class MapApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam

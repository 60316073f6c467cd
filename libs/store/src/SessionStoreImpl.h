#pragma once
/** \file SessionStoreImpl.h
 * SessionStore's private state, shared by SessionStore.cpp (open, create, checks, meta),
 * SessionStore_write.cpp and SessionStore_read.cpp. Internal to keygrid_store.
 */
#include <keygrid/store/SessionStore.h>

#include <map>
#include <memory>
#include <string>
#include <unordered_map>

#include "Sqlite.h"

namespace keygrid::store
{
struct SessionStore::Impl
{
	Impl(const std::string& p, int flags, Mode m) : db(p, flags), mode(m) {}

	detail::SqliteDb db;
	Mode mode;
	SessionMeta meta;
	/** cameras table, loaded on open and extended by write() */
	std::map<std::int64_t, core::RgbdCamera> cameras;
	/** Prepared statements by SQL text, prepared once and reused */
	std::unordered_map<std::string, detail::SqliteStatement> statements;

	detail::SqliteStatement& statement(const std::string& sql)
	{
		auto it = statements.find(sql);
		if (it == statements.end()) it = statements.emplace(sql, detail::SqliteStatement(db, sql, true)).first;
		it->second.reset();
		return it->second;
	}
	/** Id of `cam` in the cameras table, inserting it when new (inside the caller's transaction). */
	std::int64_t cameraId(const core::RgbdCamera& cam);
	void loadCameras();
	void loadMeta();
	void writeMeta();
};

namespace detail
{
/** Exact equality of every field (cameras are deduplicated by it). */
bool sameCamera(const core::RgbdCamera& a, const core::RgbdCamera& b);
/** 12 doubles: R row-major, then t (bit-exact round trip of CPose3D's matrix). */
std::vector<std::uint8_t> packPose(const mrpt::poses::CPose3D& p);
mrpt::poses::CPose3D unpackPose(const std::uint8_t* data, std::size_t bytes, const std::string& what);
}  // namespace detail

}  // namespace keygrid::store

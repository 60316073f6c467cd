#pragma once
/** \file SessionStoreOptions.h
 * How a SessionStore talks to its SQLite file (INI section `[store]`).
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>

#include <string>

namespace keygrid::store
{
struct SessionStoreOptions : public core::FieldTableOptions<SessionStoreOptions>
{
	/** When a committed write() is on disk, SQLite's `PRAGMA synchronous` in WAL mode:
	 * - "full": every commit fsyncs the write-ahead log, so a committed keyframe survives a
	 *   power loss or kernel crash as well as a killed process;
	 * - "normal": the log is fsynced only at checkpoints; a killed process (SIGKILL, crash) loses
	 *   nothing committed, a power loss may lose the last commits (the file stays consistent).
	 * A robot loses power more often than a desktop, and one fsync per keyframe (about 1 per
	 * second) is cheap next to mapping, hence "full" (Default: full) */
	std::string durability{"full"};
	/** SQLite page cache per connection [KiB], >= 64 (Default: 8192) */
	int cacheSizeKiB{8192};
	/** How long a statement waits for a lock held by another connection [ms], >= 0 (Default: 5000) */
	int busyTimeoutMs{5000};
	/** What Open() checks beyond application id and schema version: "quick" runs SQLite's
	 * `PRAGMA quick_check`, which reads every page of the file (images included); "none" skips
	 * it, for large sessions on slow storage (SessionStore::Check always runs it)
	 * (Default: quick) */
	std::string integrityCheck{"quick"};

	/** Its keys (in [store]). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "store") const;
};

}  // namespace keygrid::store

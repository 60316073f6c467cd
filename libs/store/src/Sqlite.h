#pragma once
/** \file Sqlite.h
 * Minimal RAII wrappers over the SQLite C API (internal to keygrid_store). Every error throws
 * std::runtime_error naming the database file and SQLite's message.
 */
#include <sqlite3.h>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::store::detail
{
class SqliteDb;

/** A prepared statement; reset() after each use lets it be reused without re-preparing. */
class SqliteStatement
{
   public:
	SqliteStatement() = default;
	SqliteStatement(SqliteDb& db, const std::string& sql, bool persistent);
	SqliteStatement(SqliteStatement&& o) noexcept;
	SqliteStatement& operator=(SqliteStatement&& o) noexcept;
	SqliteStatement(const SqliteStatement&) = delete;
	SqliteStatement& operator=(const SqliteStatement&) = delete;
	~SqliteStatement();

	bool valid() const { return m_stmt != nullptr; }
	/** Binds parameter i (1-based). */
	SqliteStatement& bind(int i, std::int64_t v);
	SqliteStatement& bind(int i, double v);
	SqliteStatement& bind(int i, const std::string& v);
	SqliteStatement& bindBlob(int i, const void* data, std::size_t bytes);
	SqliteStatement& bindBlob(int i, const std::vector<std::uint8_t>& v) { return bindBlob(i, v.data(), v.size()); }
	SqliteStatement& bindNull(int i);
	/** Next row: true when a row is available, false when done. */
	bool step();
	/** Runs a statement that returns no rows, then resets it. */
	void run();
	/** Clears bindings and rewinds for the next use. */
	void reset();

	bool isNull(int col) const;
	std::int64_t int64(int col) const;
	double real(int col) const;
	std::string text(int col) const;
	/** Pointer to and size of a BLOB column (valid until the next step/reset). */
	const std::uint8_t* blob(int col, std::size_t& bytes) const;
	std::vector<std::uint8_t> blobVector(int col) const;

   private:
	SqliteDb* m_db{nullptr};
	sqlite3_stmt* m_stmt{nullptr};
};

class SqliteDb
{
   public:
	/** Opens (flags: SQLITE_OPEN_*) the file; throws naming it on failure. */
	SqliteDb(const std::string& path, int flags);
	SqliteDb(const SqliteDb&) = delete;
	SqliteDb& operator=(const SqliteDb&) = delete;
	~SqliteDb();

	const std::string& path() const { return m_path; }
	sqlite3* handle() { return m_db; }
	/** Runs one or more statements without results. */
	void exec(const std::string& sql);
	/** The first column of the first row of `sql` as text ("" when no row). */
	std::string queryText(const std::string& sql);
	std::int64_t queryInt(const std::string& sql);
	/** Throws "SQLite error on 'FILE' (<what>): <sqlite message>". */
	[[noreturn]] void fail(int rc, const std::string& what) const;

   private:
	std::string m_path;
	sqlite3* m_db{nullptr};
};

/** Commits on commit(), rolls back when destroyed before (an exception in between). */
class SqliteTransaction
{
   public:
	explicit SqliteTransaction(SqliteDb& db);
	SqliteTransaction(const SqliteTransaction&) = delete;
	SqliteTransaction& operator=(const SqliteTransaction&) = delete;
	~SqliteTransaction();
	void commit();

   private:
	SqliteDb& m_db;
	bool m_done{false};
};

}  // namespace keygrid::store::detail

#include "Sqlite.h"

#include <stdexcept>

namespace keygrid::store::detail
{
SqliteStatement::SqliteStatement(SqliteDb& db, const std::string& sql, bool persistent) : m_db(&db)
{
	const unsigned flags = persistent ? SQLITE_PREPARE_PERSISTENT : 0;
	const int rc = sqlite3_prepare_v3(db.handle(), sql.c_str(), -1, flags, &m_stmt, nullptr);
	if (rc != SQLITE_OK) db.fail(rc, "prepare '" + sql + "'");
}

SqliteStatement::SqliteStatement(SqliteStatement&& o) noexcept : m_db(o.m_db), m_stmt(o.m_stmt)
{
	o.m_stmt = nullptr;
}

SqliteStatement& SqliteStatement::operator=(SqliteStatement&& o) noexcept
{
	if (this != &o)
	{
		sqlite3_finalize(m_stmt);
		m_db = o.m_db;
		m_stmt = o.m_stmt;
		o.m_stmt = nullptr;
	}
	return *this;
}

SqliteStatement::~SqliteStatement() { sqlite3_finalize(m_stmt); }

SqliteStatement& SqliteStatement::bind(int i, std::int64_t v)
{
	const int rc = sqlite3_bind_int64(m_stmt, i, v);
	if (rc != SQLITE_OK) m_db->fail(rc, "bind");
	return *this;
}

SqliteStatement& SqliteStatement::bind(int i, double v)
{
	const int rc = sqlite3_bind_double(m_stmt, i, v);
	if (rc != SQLITE_OK) m_db->fail(rc, "bind");
	return *this;
}

SqliteStatement& SqliteStatement::bind(int i, const std::string& v)
{
	const int rc = sqlite3_bind_text(m_stmt, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
	if (rc != SQLITE_OK) m_db->fail(rc, "bind");
	return *this;
}

SqliteStatement& SqliteStatement::bindBlob(int i, const void* data, std::size_t bytes)
{
	// SQLITE_STATIC: the caller's buffer outlives the statement's execution (run/step follow
	// the binds directly), which saves a copy of every image.
	const int rc = bytes == 0 ? sqlite3_bind_zeroblob(m_stmt, i, 0)
							  : sqlite3_bind_blob64(m_stmt, i, data, bytes, SQLITE_STATIC);
	if (rc != SQLITE_OK) m_db->fail(rc, "bind");
	return *this;
}

SqliteStatement& SqliteStatement::bindNull(int i)
{
	const int rc = sqlite3_bind_null(m_stmt, i);
	if (rc != SQLITE_OK) m_db->fail(rc, "bind");
	return *this;
}

bool SqliteStatement::step()
{
	const int rc = sqlite3_step(m_stmt);
	if (rc == SQLITE_ROW) return true;
	if (rc == SQLITE_DONE) return false;
	const std::string sql = sqlite3_sql(m_stmt) ? sqlite3_sql(m_stmt) : "";
	sqlite3_reset(m_stmt);
	m_db->fail(rc, "'" + sql + "'");
}

void SqliteStatement::run()
{
	while (step())
	{
	}
	reset();
}

void SqliteStatement::reset()
{
	sqlite3_reset(m_stmt);
	sqlite3_clear_bindings(m_stmt);
}

bool SqliteStatement::isNull(int col) const { return sqlite3_column_type(m_stmt, col) == SQLITE_NULL; }
std::int64_t SqliteStatement::int64(int col) const { return sqlite3_column_int64(m_stmt, col); }
double SqliteStatement::real(int col) const { return sqlite3_column_double(m_stmt, col); }

std::string SqliteStatement::text(int col) const
{
	const auto* p = sqlite3_column_text(m_stmt, col);
	return p ? std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(sqlite3_column_bytes(m_stmt, col)))
			 : std::string();
}

const std::uint8_t* SqliteStatement::blob(int col, std::size_t& bytes) const
{
	const auto* p = static_cast<const std::uint8_t*>(sqlite3_column_blob(m_stmt, col));
	bytes = static_cast<std::size_t>(sqlite3_column_bytes(m_stmt, col));
	return p;
}

std::vector<std::uint8_t> SqliteStatement::blobVector(int col) const
{
	std::size_t n = 0;
	const auto* p = blob(col, n);
	return p ? std::vector<std::uint8_t>(p, p + n) : std::vector<std::uint8_t>();
}

SqliteDb::SqliteDb(const std::string& path, int flags) : m_path(path)
{
	const int rc = sqlite3_open_v2(path.c_str(), &m_db, flags, nullptr);
	if (rc != SQLITE_OK)
	{
		const std::string msg = m_db ? sqlite3_errmsg(m_db) : sqlite3_errstr(rc);
		sqlite3_close_v2(m_db);
		m_db = nullptr;
		throw std::runtime_error("cannot open '" + path + "': " + msg);
	}
	sqlite3_extended_result_codes(m_db, 1);
}

SqliteDb::~SqliteDb() { sqlite3_close_v2(m_db); }

void SqliteDb::exec(const std::string& sql)
{
	char* err = nullptr;
	const int rc = sqlite3_exec(m_db, sql.c_str(), nullptr, nullptr, &err);
	if (rc != SQLITE_OK)
	{
		const std::string msg = err ? err : sqlite3_errstr(rc);
		sqlite3_free(err);
		throw std::runtime_error("SQLite error on '" + m_path + "' ('" + sql + "'): " + msg);
	}
}

std::string SqliteDb::queryText(const std::string& sql)
{
	SqliteStatement st(*this, sql, false);
	return st.step() ? st.text(0) : std::string();
}

std::int64_t SqliteDb::queryInt(const std::string& sql)
{
	SqliteStatement st(*this, sql, false);
	return st.step() ? st.int64(0) : 0;
}

void SqliteDb::fail(int rc, const std::string& what) const
{
	const std::string msg = m_db ? sqlite3_errmsg(m_db) : sqlite3_errstr(rc);
	throw std::runtime_error("SQLite error on '" + m_path + "' (" + what + "): " + msg);
}

SqliteTransaction::SqliteTransaction(SqliteDb& db) : m_db(db) { m_db.exec("BEGIN IMMEDIATE"); }

SqliteTransaction::~SqliteTransaction()
{
	if (!m_done) sqlite3_exec(m_db.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void SqliteTransaction::commit()
{
	m_db.exec("COMMIT");
	m_done = true;
}

}  // namespace keygrid::store::detail

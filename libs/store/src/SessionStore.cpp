/** \file SessionStore.cpp
 * Creating and opening session files: schema, pragmas, the checks Open() makes, meta table,
 * cameras. Writing: SessionStore_write.cpp; reading: SessionStore_read.cpp.
 */
#include <keygrid/core/TumText.h>
#include <keygrid/store/SessionStore.h>

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <stdexcept>

#include "BlobCodec.h"
#include "SessionStoreImpl.h"

#ifndef KEYGRID_VERSION_STRING
#error "KEYGRID_VERSION_STRING must be defined by the build (libs/store/CMakeLists.txt)"
#endif

namespace keygrid::store
{
namespace
{
constexpr const char* kFormatName = "keygrid-session";

/** Schema version 1 (doc/session-store.md describes every column and BLOB layout). */
constexpr const char* kSchemaV1 = R"SQL(
CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT NOT NULL) WITHOUT ROWID;
CREATE TABLE cameras(
  id INTEGER PRIMARY KEY, name TEXT NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL,
  fx REAL NOT NULL, fy REAL NOT NULL, cx REAL NOT NULL, cy REAL NOT NULL,
  k1 REAL NOT NULL, k2 REAL NOT NULL, p1 REAL NOT NULL, p2 REAL NOT NULL, k3 REAL NOT NULL,
  depth_units REAL NOT NULL);
CREATE TABLE keyframes(
  id INTEGER PRIMARY KEY, frame_index INTEGER NOT NULL, stamp REAL NOT NULL, pose BLOB NOT NULL,
  parent INTEGER, camera INTEGER NOT NULL REFERENCES cameras(id),
  num_levels INTEGER NOT NULL, level_scale BLOB NOT NULL, num_keypoints INTEGER NOT NULL,
  keypoints BLOB NOT NULL, undistorted BLOB NOT NULL, keypoint_depth BLOB NOT NULL,
  descriptor_type INTEGER NOT NULL, descriptor_cols INTEGER NOT NULL, descriptors BLOB NOT NULL,
  landmarks BLOB NOT NULL, bow BLOB NOT NULL);
CREATE TABLE keyframe_images(
  keyframe INTEGER PRIMARY KEY, colour_format TEXT NOT NULL, colour BLOB NOT NULL, depth BLOB NOT NULL);
CREATE TABLE landmarks(
  id INTEGER PRIMARY KEY, x REAL NOT NULL, y REAL NOT NULL, z REAL NOT NULL,
  nx REAL NOT NULL, ny REAL NOT NULL, nz REAL NOT NULL,
  min_distance REAL NOT NULL, max_distance REAL NOT NULL, first_keyframe INTEGER NOT NULL,
  visible_count INTEGER NOT NULL, found_count INTEGER NOT NULL,
  descriptor_type INTEGER NOT NULL, descriptor BLOB NOT NULL, observations BLOB NOT NULL, hoc BLOB NOT NULL);
CREATE TABLE covisibility(
  a INTEGER NOT NULL, b INTEGER NOT NULL, weight INTEGER NOT NULL, PRIMARY KEY(a, b)) WITHOUT ROWID;
CREATE TABLE loop_constraints(
  id INTEGER PRIMARY KEY, keyframe INTEGER NOT NULL, loop_keyframe INTEGER NOT NULL,
  pose BLOB NOT NULL, information BLOB NOT NULL, score REAL NOT NULL, inliers INTEGER NOT NULL);
CREATE TABLE snapshots(
  name TEXT PRIMARY KEY, last_keyframe INTEGER NOT NULL, written_utc TEXT NOT NULL,
  format TEXT NOT NULL, data BLOB NOT NULL) WITHOUT ROWID;
CREATE TABLE vocabulary(id INTEGER PRIMARY KEY CHECK (id = 1), data BLOB NOT NULL);
)SQL";

std::string nowUtcIso()
{
	const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
	std::tm tm{};
	gmtime_r(&t, &tm);
	char buf[32];
	std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
	return buf;
}

std::string exactText(double v)
{
	char buf[40];
	std::snprintf(buf, sizeof(buf), "%.17g", v);
	return buf;
}

double metaNumber(const std::string& s, const std::string& key, const std::string& path)
{
	double v = 0;
	if (!core::parseDouble(s, v))
		throw std::runtime_error("'" + path + "': meta key '" + key + "' is not a number: '" + s + "'");
	return v;
}

void applyPragmas(detail::SqliteDb& db, const SessionStoreOptions& opts, bool writable)
{
	db.exec("PRAGMA cache_size = -" + std::to_string(opts.cacheSizeKiB));
	sqlite3_busy_timeout(db.handle(), opts.busyTimeoutMs);
	if (writable)
	{
		const std::string mode = db.queryText("PRAGMA journal_mode = WAL");
		if (mode != "wal")
			throw std::runtime_error("'" + db.path() + "': cannot switch to WAL journal mode (got '" + mode + "')");
		db.exec(std::string("PRAGMA synchronous = ") + (opts.durability == "normal" ? "NORMAL" : "FULL"));
	}
}

void validateOptions(const SessionStoreOptions& opts)
{
	opts.validate();
}

/** Application id, schema version and (when quickCheck) SQLite's structural check, in that
 * order (the first two are one page read each; quick_check reads the whole file). */
void checkOpenedFile(detail::SqliteDb& db, bool quickCheck)
{
	const std::string& path = db.path();
	std::int64_t appId = 0;
	try
	{
		appId = db.queryInt("PRAGMA application_id");
	}
	catch (const std::runtime_error& e)
	{
		// SQLITE_NOTADB: not a database at all; SQLITE_CORRUPT: a database whose first pages
		// are damaged (e.g. a truncated file).
		if ((sqlite3_errcode(db.handle()) & 0xff) == SQLITE_CORRUPT)
			throw std::runtime_error("'" + path + "' is damaged (" + e.what() + ")");
		throw std::runtime_error("'" + path + "' is not a keygrid session (cannot read it as an SQLite database: " + e.what() + ")");
	}
	if (appId != SessionStore::kApplicationId)
	{
		char buf[96];
		std::snprintf(buf, sizeof(buf), "SQLite application_id 0x%08" PRIX64 ", expected 0x%08X", static_cast<std::uint64_t>(appId),
					  static_cast<unsigned>(SessionStore::kApplicationId));
		throw std::runtime_error("'" + path + "' is not a keygrid session (" + buf + ")");
	}
	std::string version;
	try
	{
		version = db.queryText("SELECT value FROM meta WHERE key = 'schema_version'");
	}
	catch (const std::runtime_error& e)
	{
		throw std::runtime_error("'" + path + "' is damaged: cannot read its meta table (" + e.what() + ")");
	}
	if (version != std::to_string(SessionStore::kSchemaVersion))
		throw std::runtime_error("'" + path + "' has session schema version " + (version.empty() ? "(none)" : version) +
								 "; this keygrid (" KEYGRID_VERSION_STRING ") reads version " +
								 std::to_string(SessionStore::kSchemaVersion));
	if (!quickCheck) return;
	std::string check;
	try
	{
		check = db.queryText("PRAGMA quick_check(1)");
	}
	catch (const std::runtime_error& e)
	{
		throw std::runtime_error("'" + path + "' is damaged (" + e.what() + ")");
	}
	if (check != "ok") throw std::runtime_error("'" + path + "' is damaged (SQLite quick_check: " + check + ")");
}

}  // namespace

namespace detail
{
bool sameCamera(const core::RgbdCamera& a, const core::RgbdCamera& b)
{
	return a.name == b.name && a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
		   a.cx == b.cx && a.cy == b.cy && a.dist == b.dist && a.depthUnits == b.depthUnits;
}

std::vector<std::uint8_t> packPose(const mrpt::poses::CPose3D& p)
{
	BlobWriter w(12 * sizeof(double));
	const auto& R = p.getRotationMatrix();
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) w.put<double>(R(r, c));
	w.put<double>(p.x());
	w.put<double>(p.y());
	w.put<double>(p.z());
	return std::move(w.bytes());
}

mrpt::poses::CPose3D unpackPose(const std::uint8_t* data, std::size_t bytes, const std::string& what)
{
	BlobReader rd(data, bytes, what);
	mrpt::math::CMatrixDouble33 R;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) R(r, c) = rd.get<double>();
	mrpt::math::CVectorFixedDouble<3> t;
	for (int i = 0; i < 3; i++) t[i] = rd.get<double>();
	if (!rd.atEnd()) throw std::runtime_error(what + ": " + std::to_string(bytes) + " bytes, expected 96");
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}
}  // namespace detail

std::int64_t SessionStore::Impl::cameraId(const core::RgbdCamera& cam)
{
	for (const auto& [id, c] : cameras)
		if (detail::sameCamera(c, cam)) return id;
	const std::int64_t id = cameras.empty() ? 1 : cameras.rbegin()->first + 1;
	auto& st = statement(
		"INSERT INTO cameras(id, name, width, height, fx, fy, cx, cy, k1, k2, p1, p2, k3, depth_units) "
		"VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)");
	st.bind(1, id).bind(2, cam.name).bind(3, std::int64_t(cam.width)).bind(4, std::int64_t(cam.height));
	st.bind(5, cam.fx).bind(6, cam.fy).bind(7, cam.cx).bind(8, cam.cy);
	for (int i = 0; i < 5; i++) st.bind(9 + i, cam.dist[static_cast<std::size_t>(i)]);
	st.bind(14, static_cast<double>(cam.depthUnits));
	st.run();
	cameras[id] = cam;
	return id;
}

void SessionStore::Impl::loadCameras()
{
	cameras.clear();
	auto& st = statement("SELECT id, name, width, height, fx, fy, cx, cy, k1, k2, p1, p2, k3, depth_units FROM cameras");
	while (st.step())
	{
		core::RgbdCamera c;
		c.name = st.text(1);
		c.width = static_cast<unsigned>(st.int64(2));
		c.height = static_cast<unsigned>(st.int64(3));
		c.fx = st.real(4);
		c.fy = st.real(5);
		c.cx = st.real(6);
		c.cy = st.real(7);
		for (int i = 0; i < 5; i++) c.dist[static_cast<std::size_t>(i)] = st.real(8 + i);
		c.depthUnits = static_cast<float>(st.real(13));
		cameras[st.int64(0)] = c;
	}
	st.reset();
}

void SessionStore::Impl::writeMeta()
{
	const auto& m = meta;
	const auto& c = m.camera;
	const std::vector<std::pair<std::string, std::string>> rows = {
		{"format", kFormatName},
		{"schema_version", std::to_string(m.schemaVersion)},
		{"keygrid_version", m.keygridVersion},
		{"created_utc", m.createdUtc},
		{"vocabulary_file", m.vocabulary.fileName},
		{"vocabulary_hash", m.vocabulary.hash},
		{"vocabulary_words", std::to_string(m.vocabulary.words)},
		{"camera_name", c.name},
		{"camera_width", std::to_string(c.width)},
		{"camera_height", std::to_string(c.height)},
		{"camera_fx", exactText(c.fx)},
		{"camera_fy", exactText(c.fy)},
		{"camera_cx", exactText(c.cx)},
		{"camera_cy", exactText(c.cy)},
		{"camera_k1", exactText(c.dist[0])},
		{"camera_k2", exactText(c.dist[1])},
		{"camera_p1", exactText(c.dist[2])},
		{"camera_p2", exactText(c.dist[3])},
		{"camera_k3", exactText(c.dist[4])},
		{"camera_depth_units", exactText(c.depthUnits)}};
	auto& st = statement("INSERT INTO meta(key, value) VALUES(?1, ?2) ON CONFLICT(key) DO UPDATE SET value = excluded.value");
	for (const auto& [k, v] : rows)
	{
		st.bind(1, k).bind(2, v);
		st.run();
	}
}

void SessionStore::Impl::loadMeta()
{
	std::map<std::string, std::string> kv;
	auto& st = statement("SELECT key, value FROM meta");
	while (st.step()) kv[st.text(0)] = st.text(1);
	st.reset();
	const std::string& path = db.path();
	const auto get = [&](const std::string& key) -> const std::string& {
		const auto it = kv.find(key);
		if (it == kv.end()) throw std::runtime_error("'" + path + "' is damaged: meta key '" + key + "' is missing");
		return it->second;
	};
	const auto num = [&](const std::string& key) { return metaNumber(get(key), key, path); };
	if (get("format") != kFormatName)
		throw std::runtime_error("'" + path + "' is not a keygrid session (meta format '" + get("format") + "')");
	meta.schemaVersion = static_cast<int>(num("schema_version"));
	meta.keygridVersion = get("keygrid_version");
	meta.createdUtc = get("created_utc");
	meta.vocabulary.fileName = get("vocabulary_file");
	meta.vocabulary.hash = get("vocabulary_hash");
	meta.vocabulary.words = static_cast<std::uint64_t>(num("vocabulary_words"));
	auto& c = meta.camera;
	c.name = get("camera_name");
	c.width = static_cast<unsigned>(num("camera_width"));
	c.height = static_cast<unsigned>(num("camera_height"));
	c.fx = num("camera_fx");
	c.fy = num("camera_fy");
	c.cx = num("camera_cx");
	c.cy = num("camera_cy");
	c.dist = {num("camera_k1"), num("camera_k2"), num("camera_p1"), num("camera_p2"), num("camera_k3")};
	c.depthUnits = static_cast<float>(num("camera_depth_units"));
	meta.attributes.clear();
	for (const auto& [k, v] : kv)
		if (k.rfind("run.", 0) == 0) meta.attributes[k] = v;
}

SessionStore::SessionStore(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
SessionStore::SessionStore(SessionStore&&) noexcept = default;
SessionStore& SessionStore::operator=(SessionStore&&) noexcept = default;
SessionStore::~SessionStore() = default;

SessionStore SessionStore::Create(const std::string& path, const SessionMeta& meta, const SessionStoreOptions& opts)
{
	validateOptions(opts);
	std::string why;
	if (!meta.camera.isValid(&why)) throw std::invalid_argument("SessionStore::Create('" + path + "'): camera: " + why);
	if (std::filesystem::exists(path))
		throw std::runtime_error("SessionStore::Create: '" + path + "' already exists (open it to extend it, or remove it)");
	auto impl = std::make_unique<Impl>(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, Mode::ReadWrite);
	try
	{
		applyPragmas(impl->db, opts, true);
		impl->meta = meta;
		impl->meta.schemaVersion = kSchemaVersion;
		impl->meta.keygridVersion = KEYGRID_VERSION_STRING;
		impl->meta.createdUtc = nowUtcIso();
		detail::SqliteTransaction tx(impl->db);
		impl->db.exec(kSchemaV1);
		impl->db.exec("PRAGMA application_id = " + std::to_string(kApplicationId));
		impl->db.exec("PRAGMA user_version = " + std::to_string(kSchemaVersion));
		impl->writeMeta();
		impl->cameraId(impl->meta.camera);
		tx.commit();
	}
	catch (...)
	{
		// A file without its schema is no session: do not leave it behind.
		impl.reset();
		std::error_code ec;
		for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix, ec);
		throw;
	}
	return SessionStore(std::move(impl));
}

SessionStore SessionStore::Open(const std::string& path, Mode mode, const SessionStoreOptions& opts)
{
	validateOptions(opts);
	if (!std::filesystem::is_regular_file(path))
		throw std::runtime_error("SessionStore: '" + path + "' does not exist or is not a file");
	const bool writable = mode == Mode::ReadWrite;
	const int flags = (writable ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY) | SQLITE_OPEN_NOMUTEX;
	auto impl = std::make_unique<Impl>(path, flags, mode);
	sqlite3_busy_timeout(impl->db.handle(), opts.busyTimeoutMs);
	checkOpenedFile(impl->db, opts.integrityCheck == "quick");
	applyPragmas(impl->db, opts, writable);
	impl->loadMeta();
	impl->loadCameras();
	return SessionStore(std::move(impl));
}

void SessionStore::Check(const std::string& path)
{
	SessionStoreOptions opts;
	opts.integrityCheck = "quick";
	Open(path, Mode::ReadOnly, opts);
}

const std::string& SessionStore::path() const { return m_impl->db.path(); }
const SessionMeta& SessionStore::meta() const { return m_impl->meta; }
SessionStore::Mode SessionStore::mode() const { return m_impl->mode; }

}  // namespace keygrid::store

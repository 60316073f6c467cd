#pragma once
/** \file SessionStore.h
 * A mapping session on disk: one SQLite file in WAL mode, written incrementally (one
 * transaction per write(), typically one keyframe with the landmarks and edges it created or
 * changed), so a process killed at any moment leaves a consistent session up to its last
 * committed write. Schema, units and version policy: doc/session-store.md.
 *
 * Reading never loads images unless asked (loadImages), so a session's cold data stays on disk.
 * A SessionStore is one connection: use it from one thread at a time (several SessionStore
 * objects, also in several processes, may read one file while one of them writes).
 */
#include <keygrid/loop/Vocabulary.h>
#include <keygrid/store/SessionRecords.h>
#include <keygrid/store/SessionStoreOptions.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::store
{
class SessionStore
{
   public:
	/** Schema version written by this build; Open() throws on a file of any other version. */
	static constexpr int kSchemaVersion = 1;
	/** SQLite `PRAGMA application_id` of a keygrid session file ("KGSS"). */
	static constexpr int kApplicationId = 0x4B475353;

	enum class Mode
	{
		ReadOnly,  //!< never changes the file (localization)
		ReadWrite  //!< write() allowed (extend a session)
	};

	/** Creates a new session file. `meta.schemaVersion`, `keygridVersion` and `createdUtc` are
	 * filled in here. Throws std::runtime_error naming the file when it already exists or
	 * cannot be created, std::invalid_argument on invalid options. */
	static SessionStore Create(
		const std::string& path, const SessionMeta& meta, const SessionStoreOptions& opts = {});
	/** Opens an existing session. Throws std::runtime_error naming the file and the reason when
	 * it does not exist, is not an SQLite database, is not a keygrid session, has another schema
	 * version (naming both), or fails SQLite's integrity check (`PRAGMA quick_check`, unless
	 * opts.integrityCheck = "none"). */
	static SessionStore Open(
		const std::string& path, Mode mode = Mode::ReadOnly, const SessionStoreOptions& opts = {});
	/** Runs every check of Open(), quick_check included, without keeping the file open; throws
	 * like Open(). */
	static void Check(const std::string& path);

	SessionStore(SessionStore&&) noexcept;
	SessionStore& operator=(SessionStore&&) noexcept;
	~SessionStore();

	const std::string& path() const;
	const SessionMeta& meta() const;
	Mode mode() const;

	/** Commits everything in `u` in one transaction (all or nothing). Throws std::logic_error
	 * on a read-only store, std::runtime_error naming the file on an SQLite error (the
	 * transaction is rolled back). */
	void write(const SessionUpdate& u);
	/** Replaces the vocabulary identity (a vocabulary file the session refers to by name and
	 * hash). Throws std::logic_error on a read-only store. */
	void setVocabulary(const VocabularyIdentity& vocabulary);
	/** Stores the vocabulary itself in the file (e.g. one trained in-run, which exists nowhere
	 * else) and sets the identity to it, in one transaction. */
	void storeVocabulary(const loop::Vocabulary& vocabulary, const std::string& name);
	/** The vocabulary stored by storeVocabulary(); nullopt when the file holds none. Throws
	 * std::runtime_error naming the file when its bytes do not match the identity's hash. */
	std::optional<loop::Vocabulary> loadVocabulary() const;
	bool hasStoredVocabulary() const;

	/** All keyframes by increasing id, without images. */
	std::vector<KeyFrameRecord> loadKeyFrames() const;
	/** One keyframe without images; nullopt when the id is not stored. */
	std::optional<KeyFrameRecord> loadKeyFrame(KeyFrameId id) const;
	/** The stored (encoded) images of a keyframe; empty when it has none. */
	EncodedImages loadEncodedImages(KeyFrameId id) const;
	/** The decoded images of a keyframe; empty mats when it has none. */
	KeyFrameImages loadImages(KeyFrameId id) const;
	/** All landmarks by increasing id. */
	std::vector<LandmarkRecord> loadLandmarks() const;
	/** All covisibility edges, ordered by (a, b). */
	std::vector<CovisibilityEdge> loadCovisibility() const;
	/** All loop constraints in the order they were written. */
	std::vector<LoopConstraint> loadLoopConstraints() const;
	/** Names of the stored snapshots, sorted. */
	std::vector<std::string> snapshotNames() const;
	/** One snapshot; nullopt when no snapshot has that name. */
	std::optional<MapSnapshot> loadSnapshot(const std::string& name) const;
	SessionCounts counts() const;

   private:
	struct Impl;
	explicit SessionStore(std::unique_ptr<Impl> impl);
	std::unique_ptr<Impl> m_impl;
};

}  // namespace keygrid::store

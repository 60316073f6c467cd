/** \file SessionStoreCrash_unittest.cpp
 * Crash safety: a child process writes keyframes to a session, one transaction each, and reports
 * every commit through a pipe; the parent SIGKILLs it at a random moment of the write after the
 * N-th commit, reopens the file and checks that it holds keyframes 0..M-1 (M >= N), each with
 * everything its transaction wrote: record, images, new and updated landmarks, the pose update
 * of its predecessor, its covisibility edge, loop constraints and map snapshot; then that the
 * session can be extended from there.
 */
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "StoreTestHelpers.h"
#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;

namespace
{
constexpr int kLandmarksPerKeyFrame = 100;

LandmarkId landmarkId(KeyFrameId kf, int k) { return kf * 1000 + static_cast<LandmarkId>(k); }
/** The pose write `by` gives keyframe by - 1 (a local bundle adjustment's correction). */
mrpt::poses::CPose3D correctedPose(KeyFrameId by) { return mrpt::poses::CPose3D(0.5 * by, -0.25 * by, 0.125, 0.01 * by, 0, 0); }
bool hasLoop(KeyFrameId id) { return id % 5 == 4; }

/** Write `id`: keyframe id with its images; landmarks (id, k) observed by id; landmarks
 * (id - 1, k) updated to be observed by id too; keyframe id - 1 moved; edge (id - 1, id); every
 * fifth keyframe a loop constraint to keyframe 0 and a new map_2d snapshot. */
SessionUpdate updateFor(KeyFrameId id, const EncodedImages& images)
{
	SessionUpdate u;
	u.keyframes.push_back(test::syntheticKeyFrame(id, 1000));
	u.images.push_back(images);
	for (int k = 0; k < kLandmarksPerKeyFrame; k++)
	{
		auto lm = test::syntheticLandmark(landmarkId(id, k), id, 1);
		lm.observations = {{id, k}};
		u.landmarks.push_back(lm);
		if (id > 0)
		{
			auto old = test::syntheticLandmark(landmarkId(id - 1, k), id - 1, 1);
			old.observations = {{id - 1, k}, {id, k + 500}};
			u.landmarks.push_back(old);
		}
	}
	if (id > 0)
	{
		u.poses.push_back({id - 1, correctedPose(id)});
		u.covisibility.push_back({id - 1, id, kLandmarksPerKeyFrame});
	}
	if (hasLoop(id))
	{
		LoopConstraint l;
		l.keyframe = id;
		l.loopKeyFrame = 0;
		u.loops.push_back(l);
		u.snapshots.push_back({"map_2d", id, std::vector<std::uint8_t>(50000, static_cast<std::uint8_t>(id))});
	}
	return u;
}

[[noreturn]] void childWriter(const std::string& path, const EncodedImages& images, int progressFd)
{
	try
	{
		auto store = SessionStore::Open(path, SessionStore::Mode::ReadWrite);
		for (KeyFrameId id = 0;; id++)
		{
			store.write(updateFor(id, images));
			const char ok = 'k';
			if (::write(progressFd, &ok, 1) != 1) _exit(2);
		}
	}
	catch (...)
	{
		const char err = 'e';
		[[maybe_unused]] const auto n = ::write(progressFd, &err, 1);
		_exit(1);
	}
}

/** Checks that the session holds whole writes 0..M-1; returns M. */
std::size_t checkConsistent(const std::string& path, const EncodedImages& images)
{
	const auto store = SessionStore::Open(path);
	const auto kfs = store.loadKeyFrames();
	const std::size_t M = kfs.size();
	for (std::size_t i = 0; i < M; i++)
	{
		const KeyFrameId id = i;
		auto expected = test::syntheticKeyFrame(id, 1000);
		if (i + 1 < M) expected.T_world_cam = correctedPose(id + 1);
		test::expectSameKeyFrame(expected, kfs[i]);
		EXPECT_EQ(store.loadEncodedImages(id).colour, images.colour) << "keyframe " << id;
		EXPECT_EQ(store.loadEncodedImages(id).depth, images.depth) << "keyframe " << id;
	}
	const auto lms = store.loadLandmarks();
	EXPECT_EQ(lms.size(), M * kLandmarksPerKeyFrame);
	for (const auto& lm : lms)
	{
		const KeyFrameId kf = lm.id / 1000;
		const int k = static_cast<int>(lm.id % 1000);
		std::map<KeyFrameId, int> obs = {{kf, k}};
		if (kf + 1 < M) obs[kf + 1] = k + 500;
		EXPECT_EQ(lm.observations, obs) << "landmark " << lm.id << " of " << M << " keyframes";
	}
	const auto edges = store.loadCovisibility();
	EXPECT_EQ(edges.size(), M > 0 ? M - 1 : 0);
	for (std::size_t i = 0; i < edges.size(); i++) EXPECT_TRUE(edges[i].a == i && edges[i].b == i + 1) << "edge " << i;
	std::size_t loops = 0;
	KeyFrameId lastSnapshot = 0;
	for (KeyFrameId id = 0; id < M; id++)
		if (hasLoop(id)) loops++, lastSnapshot = id;
	EXPECT_EQ(store.loadLoopConstraints().size(), loops);
	const auto snap = store.loadSnapshot("map_2d");
	EXPECT_EQ(snap.has_value(), loops > 0);
	if (snap)
	{
		EXPECT_EQ(snap->lastKeyFrame, lastSnapshot);
		EXPECT_EQ(snap->data, std::vector<std::uint8_t>(50000, static_cast<std::uint8_t>(lastSnapshot)));
	}
	return M;
}
}  // namespace

TEST(SessionStoreCrash, SigkillLeavesEveryCommittedKeyFrameComplete)
{
	const EncodedImages images = KeyFrameImageCodec().encode(test::syntheticImage(1, true), test::syntheticDepthRaw(1));
	std::mt19937 rng(25);
	const std::string dir = test::scratchDir("store_sigkill");
	for (const std::size_t N : {1u, 4u, 7u, 12u, 20u})
	{
		SCOPED_TRACE("killed after " + std::to_string(N) + " keyframes");
		const std::string path = dir + "/session_" + std::to_string(N) + ".kgmap";
		SessionMeta meta;
		meta.camera = core::RgbdCamera::Preset("fr1");
		SessionStore::Create(path, meta);

		int fds[2];
		ASSERT_EQ(::pipe(fds), 0);
		const pid_t pid = ::fork();
		ASSERT_GE(pid, 0);
		if (pid == 0)
		{
			::close(fds[0]);
			childWriter(path, images, fds[1]);
		}
		::close(fds[1]);
		using Clock = std::chrono::steady_clock;
		const auto start = Clock::now();
		std::size_t committed = 0;
		while (committed < N)
		{
			char c = 0;
			ASSERT_EQ(::read(fds[0], &c, 1), 1) << "the writer ended early";
			ASSERT_EQ(c, 'k') << "the writer failed";
			committed++;
		}
		// Kill somewhere within the next write (its duration estimated from the previous ones).
		const double perWriteUs = std::chrono::duration<double, std::micro>(Clock::now() - start).count() / N;
		std::this_thread::sleep_for(std::chrono::microseconds(
			static_cast<long>(std::uniform_real_distribution<double>(0, 1.2 * perWriteUs)(rng))));
		ASSERT_EQ(::kill(pid, SIGKILL), 0);
		int status = 0;
		ASSERT_EQ(::waitpid(pid, &status, 0), pid);
		EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
		char c = 0;
		while (::read(fds[0], &c, 1) == 1) committed++;
		::close(fds[0]);

		EXPECT_TRUE(std::filesystem::exists(path + "-wal")) << "the killed writer left its log";
		const std::size_t M = checkConsistent(path, images);
		EXPECT_GE(M, N);
		EXPECT_GE(M, committed) << "every reported commit is in the file";
		EXPECT_LE(M, committed + 1) << "at most the write under way when killed committed unreported";

		// The session can be extended where the killed writer stopped.
		{
			auto store = SessionStore::Open(path, SessionStore::Mode::ReadWrite);
			store.write(updateFor(M, images));
		}
		EXPECT_EQ(checkConsistent(path, images), M + 1);
	}
}

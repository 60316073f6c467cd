/** \file SessionStore_benchmark.cpp
 * Costs of the session store (keygrid::store, doc/session-store.md):
 * - BM_WriteKeyFrame/durability/images: one SessionStore::write() as the mapping thread makes
 *   it per keyframe: a keyframe with 1000 ORB keypoints and 32-byte descriptors, an 800-word BoW
 *   vector, 100 new and 100 updated landmarks (HOC counts included), the previous keyframe's
 *   pose, 5 covisibility edges; images = 1 adds its already encoded grey + depth PNGs (the
 *   encoding is BM_EncodeImages, meant for another thread). durability 0 = full (fsync per
 *   commit), 1 = normal. Counter file_KiB_per_kf: file size per keyframe.
 * - BM_SubmitKeyFrame: what the mapping thread pays with a SessionWriter: converting an
 *   sfm::KeyFrame (1000 keypoints) and 200 sfm::Landmarks to records and submit() with the raw
 *   images (depth in metres); encoding and committing run on the writer thread (durability
 *   full), flushed outside the timing.
 * - BM_EncodeImages/colour: KeyFrameImageCodec::encode of a 640x480 grey (0) or BGR (1) image
 *   and its 16-bit depth (PNG level 1); BM_DecodeImages: loading them back by id.
 * - BM_LoadSession/N/quick_check: Open() (application id, version, quick_check when 1) + every
 *   keyframe without images, landmark, covisibility edge and loop constraint of an N-keyframe
 *   session with images; BM_OpenSession/N: Open() alone (with quick_check).
 * Images are TUM fr1_desk's first frame when ../shared/data is present, else synthetic.
 * Stores are written under $TMPDIR (default /tmp).
 * Run: <build>/bin/keygrid_bench_store
 */
#include <benchmark/benchmark.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>
#include <keygrid/store/SessionWriter.h>
#include <keygrid/store/SparseMapRecords.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <random>

#include "SyntheticSession.h"

using namespace keygrid;
using namespace keygrid::store;
namespace fs = std::filesystem;

namespace
{
struct KeyFrameData
{
	cv::Mat colour, grey, depthRaw;
	KeyFrameRecord kf;
	std::string source;
};

/** A real frame (TUM fr1_desk) when available, its ORB features and a BoW vector. */
const KeyFrameData& keyframeData()
{
	static const KeyFrameData d = [] {
		KeyFrameData out;
		const std::string dir = std::string(KEYGRID_SHARED_DATA_DIR) + "/tum_fr1_desk_9frames";
		if (fs::is_directory(dir + "/rgb") && fs::is_directory(dir + "/depth"))
		{
			std::vector<fs::path> rgb, depth;
			for (const auto& e : fs::directory_iterator(dir + "/rgb")) rgb.push_back(e.path());
			for (const auto& e : fs::directory_iterator(dir + "/depth")) depth.push_back(e.path());
			std::sort(rgb.begin(), rgb.end());
			std::sort(depth.begin(), depth.end());
			if (!rgb.empty() && !depth.empty())
			{
				out.colour = cv::imread(rgb.front().string(), cv::IMREAD_COLOR);
				out.depthRaw = cv::imread(depth.front().string(), cv::IMREAD_UNCHANGED);
				out.source = "TUM fr1_desk " + rgb.front().filename().string();
			}
		}
		if (out.colour.empty() || out.depthRaw.type() != CV_16UC1)
		{
			out.colour = test::syntheticImage(1, true);
			out.depthRaw = test::syntheticDepthRaw(1);
			out.source = "synthetic";
		}
		cv::cvtColor(out.colour, out.grey, cv::COLOR_BGR2GRAY);
		// The record layout of a real keyframe: ORB keypoints and descriptors of the image.
		out.kf = test::syntheticKeyFrame(0, 0);
		std::vector<cv::KeyPoint> kps;
		cv::Mat desc;
		cv::ORB::create(1000)->detectAndCompute(out.grey, cv::noArray(), kps, desc);
		out.kf.keypoints = kps;
		out.kf.descriptors = desc;
		for (std::size_t i = 0; i < kps.size(); i++)
		{
			out.kf.undistorted.push_back(kps[i].pt);
			const auto raw = out.depthRaw.at<std::uint16_t>(cvRound(kps[i].pt.y), cvRound(kps[i].pt.x));
			out.kf.keypointDepth.push_back(raw * 0.0002f);
			out.kf.landmarks.push_back(i % 3 == 0 ? kNoLandmark : i);
		}
		std::mt19937 rng(3);
		std::uniform_real_distribution<double> u(0, 1);
		for (loop::WordId w = 0; w < 800; w++) out.kf.bow.push_back({w * 12 + static_cast<loop::WordId>(u(rng) * 10), u(rng) / 800});
		return out;
	}();
	return d;
}

fs::path benchDir()
{
	const fs::path d = fs::temp_directory_path() / "keygrid_bench_store";
	fs::create_directories(d);
	return d;
}

void removeStore(const fs::path& p)
{
	for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(p.string() + suffix);
}

/** The update the mapping thread writes for keyframe `id`. */
SessionUpdate keyframeUpdate(KeyFrameId id, const EncodedImages* images)
{
	SessionUpdate u;
	u.keyframes.push_back(keyframeData().kf);
	u.keyframes.back().id = id;
	u.keyframes.back().frameIndex = 10 * id;
	// Keypoint k < 100 observes the keyframe's new landmark k (as the landmarks below say).
	auto& lmOfKp = u.keyframes.back().landmarks;
	std::fill(lmOfKp.begin(), lmOfKp.end(), kNoLandmark);
	for (std::size_t k = 0; k < 100 && k < lmOfKp.size(); k++) lmOfKp[k] = id * 1000 + k;
	if (images) u.images.push_back(*images);
	for (int k = 0; k < 100; k++)
	{
		u.landmarks.push_back(test::syntheticLandmark(id * 1000 + static_cast<LandmarkId>(k), id, 1));
		if (id > 0) u.landmarks.push_back(test::syntheticLandmark((id - 1) * 1000 + static_cast<LandmarkId>(k), id - 1, 2));
	}
	if (id > 0) u.poses.push_back({id - 1, mrpt::poses::CPose3D(0.1 * id, 0, 0, 0, 0, 0)});
	for (KeyFrameId k = 1; k <= 5 && k <= id; k++) u.covisibility.push_back({id - k, id, 100 - 10 * static_cast<int>(k)});
	return u;
}

const EncodedImages& encodedGrey()
{
	static const EncodedImages e = KeyFrameImageCodec().encode(keyframeData().grey, keyframeData().depthRaw);
	return e;
}

void BM_WriteKeyFrame(benchmark::State& state)
{
	const fs::path path = benchDir() / "write.kgmap";
	removeStore(path);
	SessionStoreOptions opts;
	opts.durability = state.range(0) == 0 ? "full" : "normal";
	const bool withImages = state.range(1) != 0;
	SessionMeta meta;
	meta.camera = core::RgbdCamera::Preset("fr1");
	KeyFrameId id = 0;
	{
		auto store = SessionStore::Create(path.string(), meta, opts);
		for (auto _ : state)
		{
			state.PauseTiming();
			const SessionUpdate u = keyframeUpdate(id++, withImages ? &encodedGrey() : nullptr);
			state.ResumeTiming();
			store.write(u);
		}
	}
	state.counters["file_KiB_per_kf"] = static_cast<double>(fs::file_size(path)) / 1024.0 / static_cast<double>(id);
	state.SetLabel(keyframeData().source + ", " + std::to_string(keyframeData().kf.keypoints.size()) + " keypoints");
	removeStore(path);
}
BENCHMARK(BM_WriteKeyFrame)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"normal", "images"})->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_SubmitKeyFrame(benchmark::State& state)
{
	const fs::path path = benchDir() / "submit.kgmap";
	removeStore(path);
	SessionMeta meta;
	meta.camera = core::RgbdCamera::Preset("fr1");
	const auto& d = keyframeData();
	sfm::KeyFrame kf = toKeyFrame(d.kf);
	kf.colour = d.grey;
	kf.depth = KeyFrameImageCodec::rawToDepth(d.depthRaw, kf.features.camera.depthUnits);
	std::vector<sfm::Landmark> lms;
	for (int k = 0; k < 200; k++) lms.push_back(toLandmark(test::syntheticLandmark(static_cast<LandmarkId>(k), 0, 2)));
	KeyFrameId id = 0;
	{
		SessionWriter writer(SessionStore::Create(path.string(), meta));
		for (auto _ : state)
		{
			kf.id = id++;
			SessionWriteJob job;
			job.update.keyframes.push_back(toRecord(kf, d.kf.bow));
			for (auto& lm : lms)
			{
				lm.id += 1000;
				job.update.landmarks.push_back(toRecord(lm));
			}
			job.update.covisibility = covisibilityOf(kf);
			job.images.push_back({kf.colour, kf.depth, kf.features.camera.depthUnits});
			writer.submit(std::move(job));
			state.PauseTiming();
			writer.flush();
			state.ResumeTiming();
		}
		writer.close();
		const auto st = writer.stats();
		state.counters["writer_encode_ms"] = 1e3 * st.encodeSeconds / static_cast<double>(st.committed);
		state.counters["writer_write_ms"] = 1e3 * st.writeSeconds / static_cast<double>(st.committed);
	}
	removeStore(path);
}
BENCHMARK(BM_SubmitKeyFrame)->Iterations(100)->Unit(benchmark::kMillisecond);

void BM_EncodeImages(benchmark::State& state)
{
	const auto& d = keyframeData();
	const cv::Mat& img = state.range(0) ? d.colour : d.grey;
	const KeyFrameImageCodec codec;
	std::size_t bytes = 0;
	for (auto _ : state)
	{
		const auto e = codec.encode(img, d.depthRaw);
		bytes = e.colour.size() + e.depth.size();
		benchmark::DoNotOptimize(bytes);
	}
	state.counters["KiB"] = static_cast<double>(bytes) / 1024.0;
	state.SetLabel(d.source);
}
BENCHMARK(BM_EncodeImages)->Arg(0)->Arg(1)->ArgName("colour")->Unit(benchmark::kMillisecond);

/** An N-keyframe session with images, built once per N. */
fs::path sessionOf(int n)
{
	const fs::path path = benchDir() / ("load_" + std::to_string(n) + ".kgmap");
	static std::map<int, bool> built;
	if (!built[n])
	{
		removeStore(path);
		SessionMeta meta;
		meta.camera = core::RgbdCamera::Preset("fr1");
		auto store = SessionStore::Create(path.string(), meta);
		for (KeyFrameId id = 0; id < static_cast<KeyFrameId>(n); id++)
		{
			SessionUpdate u = keyframeUpdate(id, &encodedGrey());
			if (id % 50 == 49)
			{
				LoopConstraint l;
				l.keyframe = id;
				l.loopKeyFrame = id - 40;
				u.loops.push_back(l);
			}
			store.write(u);
		}
		built[n] = true;
	}
	return path;
}

void BM_LoadSession(benchmark::State& state)
{
	const fs::path path = sessionOf(static_cast<int>(state.range(0)));
	SessionStoreOptions opts;
	opts.integrityCheck = state.range(1) ? "quick" : "none";
	std::size_t kfs = 0, lms = 0;
	for (auto _ : state)
	{
		const auto store = SessionStore::Open(path.string(), SessionStore::Mode::ReadOnly, opts);
		const auto k = store.loadKeyFrames();
		const auto l = store.loadLandmarks();
		const auto c = store.loadCovisibility();
		const auto loops = store.loadLoopConstraints();
		kfs = k.size();
		lms = l.size();
		benchmark::DoNotOptimize(c.data());
		benchmark::DoNotOptimize(loops.data());
	}
	state.counters["keyframes"] = static_cast<double>(kfs);
	state.counters["landmarks"] = static_cast<double>(lms);
	state.counters["file_MiB"] = static_cast<double>(fs::file_size(path)) / (1024.0 * 1024.0);
}
BENCHMARK(BM_LoadSession)->ArgsProduct({{100, 400}, {1, 0}})->ArgNames({"keyframes", "quick_check"})->Unit(benchmark::kMillisecond);

void BM_OpenSession(benchmark::State& state)
{
	const fs::path path = sessionOf(static_cast<int>(state.range(0)));
	for (auto _ : state)
	{
		const auto store = SessionStore::Open(path.string());
		benchmark::DoNotOptimize(store.meta().schemaVersion);
	}
}
BENCHMARK(BM_OpenSession)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond);

void BM_DecodeImages(benchmark::State& state)
{
	const auto store = SessionStore::Open(sessionOf(400).string());
	KeyFrameId id = 0;
	for (auto _ : state)
	{
		const auto img = store.loadImages(id);
		id = (id + 37) % 400;
		benchmark::DoNotOptimize(img.depthRaw.data);
	}
}
BENCHMARK(BM_DecodeImages)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

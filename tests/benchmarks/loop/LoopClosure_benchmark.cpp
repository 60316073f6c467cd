/** \file LoopClosure_benchmark.cpp
 * Costs of the loop-closure building blocks (keygrid::loop):
 * - BM_TrainVocabulary: hierarchical k-means, 100 000 ORB descriptors, k = 10, L = 4, 1 vs 2 threads;
 * - BM_Transform: descriptors -> TF-IDF BoW vector, 1000 ORB features;
 * - BM_TransformAndQuery/N: transform + inverted-index query against N keyframes;
 * - BM_PoseGraph/N: Ceres + SuiteSparse optimisation of an N-keyframe graph with loops.
 * Keyframes are 640x480 views cropped from one large procedural texture (overlapping views
 * share features, as a real sequence does), 1000 ORB features each. With ../shared/data present,
 * BM_TransformAndQueryTum repeats the query on the 250 real frames of TUM fr1_rpy.
 */
#include <benchmark/benchmark.h>
#include <keygrid/loop/DirectIndexMatcher.h>
#include <keygrid/loop/KeyFrameDatabase.h>
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/Vocabulary.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

using namespace keygrid::loop;

namespace
{
cv::Mat proceduralWorld(std::uint64_t seed)
{
	std::mt19937_64 rng(seed);
	const int W = 4000, H = 3000;
	std::uniform_int_distribution<int> x(0, W - 1), y(0, H - 1), r(3, 40), g(0, 255);
	cv::Mat img(H, W, CV_8U, cv::Scalar(128));
	for (int i = 0; i < 60000; ++i)
	{
		if (i % 3 == 0) cv::rectangle(img, cv::Rect(x(rng), y(rng), r(rng), r(rng)), cv::Scalar(g(rng)), cv::FILLED);
		else if (i % 3 == 1) cv::circle(img, cv::Point(x(rng), y(rng)), r(rng), cv::Scalar(g(rng)), cv::FILLED);
		else cv::line(img, cv::Point(x(rng), y(rng)), cv::Point(x(rng), y(rng)), cv::Scalar(g(rng)), 2);
	}
	return img;
}

/** 1000-feature ORB descriptors of `count` random 640x480 views of the procedural world. */
const std::vector<cv::Mat>& keyframeDescriptors()
{
	static const std::vector<cv::Mat> all = [] {
		const cv::Mat world = proceduralWorld(1);
		auto orb = cv::ORB::create(1000);
		std::mt19937_64 rng(2);
		std::uniform_int_distribution<int> x(0, world.cols - 640), y(0, world.rows - 480);
		std::vector<cv::Mat> out;
		for (int i = 0; i < 1000; ++i)
		{
			std::vector<cv::KeyPoint> kps;
			cv::Mat d;
			orb->detectAndCompute(world(cv::Rect(x(rng), y(rng), 640, 480)), cv::noArray(), kps, d);
			out.push_back(d);
		}
		return out;
	}();
	return all;
}

/** Training set: the first 100 views (~100 000 descriptors). */
std::vector<cv::Mat> trainingSet()
{
	const auto& all = keyframeDescriptors();
	return std::vector<cv::Mat>(all.begin(), all.begin() + 100);
}

const Vocabulary& vocabulary()
{
	static const Vocabulary v = [] {
		VocabularyOptions o;
		o.branching = 10;
		o.levels = 4;
		return Vocabulary::train(trainingSet(), o);
	}();
	return v;
}

void BM_TrainVocabulary(benchmark::State& st)
{
	const auto train = trainingSet();
	std::size_t n = 0;
	for (const auto& d : train) n += static_cast<std::size_t>(d.rows);
	VocabularyOptions o;
	o.branching = 10;
	o.levels = 4;
	o.threads = static_cast<int>(st.range(0));
	for (auto _ : st)
	{
		const Vocabulary v = Vocabulary::train(train, o);
		benchmark::DoNotOptimize(v.numWords());
		st.counters["words"] = static_cast<double>(v.numWords());
	}
	st.counters["descriptors"] = static_cast<double>(n);
}
BENCHMARK(BM_TrainVocabulary)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

void BM_Transform(benchmark::State& st)
{
	const auto& v = vocabulary();
	const cv::Mat& d = keyframeDescriptors()[500];
	for (auto _ : st) benchmark::DoNotOptimize(v.transform(d));
	st.counters["features"] = d.rows;
}
BENCHMARK(BM_Transform)->Unit(benchmark::kMicrosecond);

void BM_TransformAndQuery(benchmark::State& st)
{
	const auto& v = vocabulary();
	const auto& all = keyframeDescriptors();
	const auto n = static_cast<std::size_t>(st.range(0));
	KeyFrameDatabase db;
	for (std::size_t i = 0; i < n; ++i) db.add(i, v.transform(all[i]));
	std::size_t q = 0, candidates = 0;
	for (auto _ : st)
	{
		const cv::Mat& d = all[all.size() - 1 - (q++ % 100)];  // views not in the database
		const auto res = db.query(v.transform(d));
		candidates += res.size();
		benchmark::DoNotOptimize(res.data());
	}
	st.counters["keyframes"] = static_cast<double>(n);
	st.counters["candidates"] = static_cast<double>(candidates) / static_cast<double>(st.iterations());
}
BENCHMARK(BM_TransformAndQuery)->Arg(100)->Arg(500)->Arg(900)->Unit(benchmark::kMicrosecond);

/** Direct-index matching of two 1000-feature keyframes (a view against itself with 2 bits of
 * noise per descriptor), nodes at depth st.range(0). */
void BM_MatchByDirectIndex(benchmark::State& st)
{
	const auto& v = vocabulary();
	const cv::Mat a = keyframeDescriptors()[500];
	cv::Mat b = a.clone();
	std::mt19937_64 rng(4);
	std::uniform_int_distribution<int> bit(0, 255);
	for (int r = 0; r < b.rows; ++r)
		for (int k = 0; k < 2; ++k)
		{
			const int x = bit(rng);
			b.at<uchar>(r, x / 8) ^= static_cast<uchar>(1u << (x % 8));
		}
	FeatureVector fa, fb;
	v.transform(a, fa, static_cast<int>(st.range(0)));
	v.transform(b, fb, static_cast<int>(st.range(0)));
	std::size_t matches = 0;
	for (auto _ : st)
	{
		const auto m = matchByDirectIndex(a, fa, b, fb);
		matches = m.size();
		benchmark::DoNotOptimize(m.data());
	}
	st.counters["matches"] = static_cast<double>(matches);
}
BENCHMARK(BM_MatchByDirectIndex)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

/** TUM fr1_rpy (250 frames) from ../shared/data: vocabulary trained on the sequence itself. */
void BM_TransformAndQueryTum(benchmark::State& st)
{
	namespace fs = std::filesystem;
	const fs::path dir = fs::path(KEYGRID_SHARED_DATA_DIR) / "tum_fr1_rpy_first250" / "rgb";
	if (!fs::is_directory(dir))
	{
		st.SkipWithError("shared data tum_fr1_rpy_first250 not found");
		for (auto _ : st) {}
		return;
	}
	std::vector<fs::path> files;
	for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
	std::sort(files.begin(), files.end());
	auto orb = cv::ORB::create(1000);
	std::vector<cv::Mat> desc;
	for (const auto& f : files)
	{
		std::vector<cv::KeyPoint> kps;
		cv::Mat d;
		orb->detectAndCompute(cv::imread(f.string(), cv::IMREAD_GRAYSCALE), cv::noArray(), kps, d);
		desc.push_back(d);
	}
	VocabularyOptions o;
	const Vocabulary v = Vocabulary::train(desc, o);
	KeyFrameDatabase db;
	for (std::size_t i = 0; i < desc.size(); ++i) db.add(i, v.transform(desc[i]));
	std::size_t q = 0;
	for (auto _ : st)
	{
		const auto res = db.query(v.transform(desc[q++ % desc.size()]));
		benchmark::DoNotOptimize(res.data());
	}
	st.counters["keyframes"] = static_cast<double>(desc.size());
}
BENCHMARK(BM_TransformAndQueryTum)->Unit(benchmark::kMicrosecond);

/** n keyframes on a 10-lap helix (radius 5 m), noisy odometry edges i -> i+1, covisibility
 * edges i -> i+2 and a loop edge every 10 keyframes to the same place one lap earlier. */
PoseGraph helixGraph(int n)
{
	std::mt19937_64 rng(3);
	std::normal_distribution<double> g(0.0, 1.0);
	const int perLap = std::max(10, n / 10);
	std::vector<Eigen::Isometry3d> gt;
	for (int i = 0; i < n; ++i)
	{
		const double th = 2 * M_PI * i / perLap;
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		T.linear() = Eigen::AngleAxisd(th + M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
		T.translation() = Eigen::Vector3d(5 * std::cos(th), 5 * std::sin(th), 0.01 * i / perLap);
		gt.push_back(T);
	}
	auto noisy = [&](const Eigen::Isometry3d& T, double st, double sr) {
		Eigen::Isometry3d N = Eigen::Isometry3d::Identity();
		const Eigen::Vector3d r(sr * g(rng), sr * g(rng), sr * g(rng));
		N.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
		N.translation() = Eigen::Vector3d(st * g(rng), st * g(rng), st * g(rng));
		return T * N;
	};
	Matrix6d info = Matrix6d::Identity();
	info.diagonal() << 2500, 2500, 2500, 10000, 10000, 10000;  // 2 cm, 0.01 rad
	PoseGraph pg;
	Eigen::Isometry3d T = gt[0];
	pg.addVertex(0, T);
	for (int i = 1; i < n; ++i)
	{
		const Eigen::Isometry3d meas = noisy(gt[static_cast<std::size_t>(i - 1)].inverse() * gt[static_cast<std::size_t>(i)], 0.02, 0.01);
		T = T * meas;
		pg.addVertex(static_cast<KeyFrameId>(i), T);
		pg.addEdge(PoseGraphEdge{static_cast<KeyFrameId>(i - 1), static_cast<KeyFrameId>(i), meas, info, EdgeKind::Odometry});
	}
	for (int i = 2; i < n; ++i)
		pg.addEdge(PoseGraphEdge{static_cast<KeyFrameId>(i - 2), static_cast<KeyFrameId>(i),
			noisy(gt[static_cast<std::size_t>(i - 2)].inverse() * gt[static_cast<std::size_t>(i)], 0.02, 0.01), info, EdgeKind::Covisibility});
	for (int i = perLap; i < n; i += 10)
		pg.addEdge(PoseGraphEdge{static_cast<KeyFrameId>(i - perLap), static_cast<KeyFrameId>(i),
			noisy(gt[static_cast<std::size_t>(i - perLap)].inverse() * gt[static_cast<std::size_t>(i)], 0.01, 0.005), info, EdgeKind::Loop});
	return pg;
}

void BM_PoseGraph(benchmark::State& st)
{
	const PoseGraph g0 = helixGraph(static_cast<int>(st.range(0)));
	int iterations = 0;
	double costRatio = 0;
	for (auto _ : st)
	{
		st.PauseTiming();
		PoseGraph g = g0;
		st.ResumeTiming();
		const auto s = g.optimize();
		iterations = s.iterations;
		costRatio = s.finalCost / s.initialCost;
	}
	st.counters["edges"] = static_cast<double>(g0.edges().size());
	st.counters["lm_iterations"] = iterations;
	st.counters["cost_ratio"] = costRatio;
}
BENCHMARK(BM_PoseGraph)->Arg(100)->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

/** \file VocabularyTraining.cpp
 * Hierarchical k-means (k-means++ seeding + Lloyd iterations) that builds the vocabulary tree,
 * then the idf weights from the training images.
 *
 * Determinism: every node's k-means draws from its own generator, seeded from the options' seed
 * and the node's path in the tree (child index at each level). Threads only decide which subtree
 * is built when, never what it contains, so the tree is identical for any thread count.
 */
#include "DescriptorMetric.h"

#include <keygrid/loop/Vocabulary.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>

namespace keygrid::loop
{
namespace detail
{
/** Tree node during training (before flattening). */
struct VocabBuildNode
{
	cv::Mat centre;  //!< 1 row, empty for the root
	std::vector<VocabBuildNode> children;
};
}  // namespace detail
using BuildNode = detail::VocabBuildNode;

namespace
{
/** splitmix64 finaliser: decorrelates the seeds of sibling nodes. */
std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t child)
{
	std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (child + 1);
	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
	return z ^ (z >> 31);
}

/** Runs fn(begin, end) over [0, n) split into `threads` contiguous chunks. */
template <class Fn>
void parallelRanges(std::size_t n, int threads, const Fn& fn)
{
	if (threads <= 1 || n < 2048)
	{
		fn(std::size_t(0), n);
		return;
	}
	std::vector<std::thread> pool;
	const std::size_t chunk = (n + static_cast<std::size_t>(threads) - 1) / static_cast<std::size_t>(threads);
	for (int t = 0; t < threads; ++t)
	{
		const std::size_t b = std::min(n, chunk * static_cast<std::size_t>(t));
		const std::size_t e = std::min(n, b + chunk);
		if (b < e) pool.emplace_back([&fn, b, e] { fn(b, e); });
	}
	for (auto& th : pool) th.join();
}

template <class Metric>
class TreeBuilder
{
   public:
	TreeBuilder(const Metric& m, const cv::Mat& data, const VocabularyOptions& o)
		: m_metric(m), m_data(data), m_opts(o)
	{
	}

	/** k-means of the rows idx into at most k non-empty clusters; returns their members and
	 * writes their centres (one row each). `threads` parallelises the assignment step. */
	std::vector<std::vector<int>> kmeans(
		const std::vector<int>& idx, std::uint64_t seed, int threads, std::vector<cv::Mat>& centresOut) const
	{
		const int k = m_opts.branching;
		const std::size_t n = idx.size();
		std::mt19937_64 rng(seed);
		cv::Mat centres(k, m_data.cols, m_data.type());
		const std::size_t rowBytes = m_data.cols * m_data.elemSize();
		auto setCentre = [&](int c, int row) { std::memcpy(centres.ptr(c), m_data.ptr(row), rowBytes); };

		// k-means++ seeding: first centre uniform, then each next one with probability
		// proportional to D(x)^2, the (squared) distance to the nearest centre chosen so far.
		int numCentres = 1;
		setCentre(0, idx[std::uniform_int_distribution<std::size_t>(0, n - 1)(rng)]);
		std::vector<double> minW(n);
		for (std::size_t i = 0; i < n; ++i)
			minW[i] = m_metric.seedingWeight(m_metric.distance(m_data.ptr(idx[i]), centres.ptr(0)));
		while (numCentres < k)
		{
			double total = 0;
			for (double w : minW) total += w;
			if (total <= 0) break;  // every point coincides with a centre: fewer clusters
			const double r = std::uniform_real_distribution<double>(0.0, total)(rng);
			double acc = 0;
			std::size_t pick = n - 1;
			for (std::size_t i = 0; i < n; ++i)
			{
				acc += minW[i];
				if (acc >= r && minW[i] > 0)
				{
					pick = i;
					break;
				}
			}
			setCentre(numCentres, idx[pick]);
			const uchar* c = centres.ptr(numCentres);
			for (std::size_t i = 0; i < n; ++i)
				minW[i] = std::min(minW[i], m_metric.seedingWeight(m_metric.distance(m_data.ptr(idx[i]), c)));
			++numCentres;
		}

		// Lloyd iterations; ends with an assignment step so that members are exactly the points
		// whose nearest centre is theirs (what the tree descent will do at query time).
		std::vector<int> assign(n, -1);
		auto assignAll = [&]() {
			std::atomic<bool> changed{false};
			parallelRanges(n, threads, [&](std::size_t b, std::size_t e) {
				bool ch = false;
				for (std::size_t i = b; i < e; ++i)
				{
					const uchar* x = m_data.ptr(idx[i]);
					int best = 0;
					double bestD = m_metric.distance(x, centres.ptr(0));
					for (int c = 1; c < numCentres; ++c)
					{
						const double d = m_metric.distance(x, centres.ptr(c));
						if (d < bestD)
						{
							bestD = d;
							best = c;
						}
					}
					if (assign[i] != best)
					{
						assign[i] = best;
						ch = true;
					}
				}
				if (ch) changed = true;
			});
			return changed.load();
		};
		std::vector<std::vector<int>> members;
		auto collect = [&]() {
			members.assign(static_cast<std::size_t>(numCentres), {});
			for (std::size_t i = 0; i < n; ++i) members[static_cast<std::size_t>(assign[i])].push_back(idx[i]);
		};
		assignAll();
		for (int it = 0; it < m_opts.maxIterations; ++it)
		{
			collect();
			for (int c = 0; c < numCentres; ++c)
			{
				const auto& mem = members[static_cast<std::size_t>(c)];
				if (!mem.empty()) m_metric.centre(m_data, mem.data(), mem.size(), centres.ptr(c));
			}
			if (!assignAll()) break;
		}
		collect();

		std::vector<std::vector<int>> clusters;
		centresOut.clear();
		for (int c = 0; c < numCentres; ++c)
		{
			if (members[static_cast<std::size_t>(c)].empty()) continue;
			clusters.push_back(std::move(members[static_cast<std::size_t>(c)]));
			centresOut.push_back(centres.row(c).clone());
		}
		return clusters;
	}

	/** Builds the subtree under `node` from the rows idx (node at depth `depth`). */
	void build(BuildNode& node, const std::vector<int>& idx, int depth, std::uint64_t seed, int threads)
	{
		if (depth >= m_opts.levels || idx.size() <= 1) return;
		if (idx.size() <= static_cast<std::size_t>(m_opts.branching))
		{
			// Too few descriptors to cluster: each becomes a word of its own.
			for (int row : idx) node.children.push_back(BuildNode{m_data.row(row).clone(), {}});
			return;
		}
		std::vector<cv::Mat> centres;
		const auto clusters = kmeans(idx, seed, threads, centres);
		if (clusters.size() <= 1) return;  // all descriptors identical: a leaf
		node.children.resize(clusters.size());
		for (std::size_t c = 0; c < clusters.size(); ++c) node.children[c].centre = centres[c];

		if (threads <= 1)
		{
			for (std::size_t c = 0; c < clusters.size(); ++c)
			{
				build(node.children[c], clusters[c], depth + 1, mixSeed(seed, c), 1);
				if (depth == 0) reportDone(clusters[c].size());
			}
			return;
		}
		// Subtrees of the children on a pool of threads; each subtree single-threaded inside.
		std::atomic<std::size_t> next{0};
		std::vector<std::thread> pool;
		for (int t = 0; t < threads; ++t)
			pool.emplace_back([&] {
				for (std::size_t c = next++; c < clusters.size(); c = next++)
				{
					build(node.children[c], clusters[c], depth + 1, mixSeed(seed, c), 1);
					if (depth == 0) reportDone(clusters[c].size());
				}
			});
		for (auto& th : pool) th.join();
	}

	void setProgress(const Vocabulary::Progress& p, std::size_t total)
	{
		m_progress = p;
		m_total = total;
	}
	void reportDone(std::size_t n)
	{
		std::lock_guard<std::mutex> lock(m_progressMutex);
		m_done += n;
		if (m_progress) m_progress(m_done, m_total);
	}

   private:
	Metric m_metric;
	const cv::Mat& m_data;
	VocabularyOptions m_opts;
	Vocabulary::Progress m_progress;
	std::size_t m_total{0}, m_done{0};
	std::mutex m_progressMutex;
};

}  // namespace

/** Flattens a BuildNode tree into the Vocabulary's arrays (breadth first, children contiguous). */
class VocabularyBuilder
{
   public:
	static void flatten(Vocabulary& v, const BuildNode& root, int cols, int type)
	{
		v.m_nodes.clear();
		v.m_words.clear();
		std::vector<const BuildNode*> bfs{&root};
		std::vector<int> depth{0};
		for (std::size_t i = 0; i < bfs.size(); ++i)
		{
			const BuildNode* bn = bfs[i];
			Vocabulary::Node n;
			n.depth = depth[i];
			n.firstChild = static_cast<std::uint32_t>(bfs.size());
			n.numChildren = static_cast<std::uint32_t>(bn->children.size());
			for (const auto& c : bn->children)
			{
				bfs.push_back(&c);
				depth.push_back(depth[i] + 1);
			}
			if (bn->children.empty() && i != 0)
			{
				n.firstChild = 0;
				n.word = static_cast<std::int32_t>(v.m_words.size());
				v.m_words.push_back(static_cast<NodeId>(i));
			}
			v.m_nodes.push_back(n);
		}
		v.m_centres = cv::Mat::zeros(static_cast<int>(bfs.size()), cols, type);
		for (std::size_t i = 1; i < bfs.size(); ++i) bfs[i]->centre.copyTo(v.m_centres.row(static_cast<int>(i)));
	}

	static void computeIdf(Vocabulary& v, const std::vector<cv::Mat>& images)
	{
		v.m_idf.assign(v.m_words.size(), 1.0);
		std::vector<std::size_t> imagesWithWord(v.m_words.size(), 0);
		std::size_t n = 0;
		for (const auto& img : images)
		{
			if (img.empty()) continue;
			++n;
			for (const auto& e : v.transform(img)) ++imagesWithWord[e.word];
		}
		v.m_trainingImages = n;
		for (std::size_t w = 0; w < v.m_words.size(); ++w)
			v.m_idf[w] = std::log(static_cast<double>(n) / static_cast<double>(std::max<std::size_t>(1, imagesWithWord[w])));
	}
};

Vocabulary Vocabulary::train(
	const std::vector<cv::Mat>& imageDescriptors, const VocabularyOptions& opts, const Progress& progress)
{
	opts.validate();
	int type = -1, cols = 0;
	std::size_t total = 0;
	for (const auto& d : imageDescriptors)
	{
		if (d.empty()) continue;
		if (d.type() != CV_8U && d.type() != CV_32F)
			throw std::invalid_argument("Vocabulary::train: descriptors must be CV_8U or CV_32F rows");
		if (type < 0)
		{
			type = d.type();
			cols = d.cols;
		}
		else if (d.type() != type || d.cols != cols)
			throw std::invalid_argument(
				"Vocabulary::train: mixed descriptor types or widths (" + std::to_string(cols) + " vs " +
				std::to_string(d.cols) + " columns)");
		total += static_cast<std::size_t>(d.rows);
	}
	if (total == 0) throw std::invalid_argument("Vocabulary::train: no descriptors");

	cv::Mat data;
	{
		std::vector<cv::Mat> nonEmpty;
		for (const auto& d : imageDescriptors)
			if (!d.empty()) nonEmpty.push_back(d.isContinuous() ? d : d.clone());
		cv::vconcat(nonEmpty, data);
	}
	std::vector<int> all(total);
	for (std::size_t i = 0; i < total; ++i) all[i] = static_cast<int>(i);
	const int threads = opts.threads > 0 ? opts.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));

	Vocabulary v;
	v.m_type = type == CV_8U ? DescriptorType::Binary : DescriptorType::Float;
	v.m_cols = cols;
	v.m_branching = opts.branching;
	v.m_levels = opts.levels;
	BuildNode root;
	if (v.m_type == DescriptorType::Binary)
	{
		TreeBuilder<detail::BinaryMetric> b(detail::BinaryMetric{cols}, data, opts);
		b.setProgress(progress, total);
		b.build(root, all, 0, opts.seed, threads);
	}
	else
	{
		TreeBuilder<detail::FloatMetric> b(detail::FloatMetric{cols}, data, opts);
		b.setProgress(progress, total);
		b.build(root, all, 0, opts.seed, threads);
	}
	if (root.children.empty())
	{
		// A single distinct descriptor: one word.
		root.children.push_back(BuildNode{data.row(0).clone(), {}});
	}
	VocabularyBuilder::flatten(v, root, cols, type);
	VocabularyBuilder::computeIdf(v, imageDescriptors);
	if (progress) progress(total, total);
	return v;
}

}  // namespace keygrid::loop

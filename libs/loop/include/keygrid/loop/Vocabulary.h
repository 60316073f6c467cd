#pragma once
/** \file Vocabulary.h
 * Vocabulary tree (Nister & Stewenius, "Scalable Recognition with a Vocabulary Tree", CVPR 2006):
 * hierarchical k-means over training descriptors, leaves are visual words weighted by their
 * inverse document frequency idf_i = log(N / n_i) (N training images, n_i of them contain word i).
 *
 * Descriptors are the rows of a cv::Mat: CV_8U (binary, e.g. ORB 32 bytes: Hamming distance,
 * bit-majority centres) or CV_32F (e.g. SIFT 128 floats: Euclidean distance, mean centres).
 * The tree is built deterministically for a given seed, whatever the number of threads.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/loop/BowVector.h>
#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace keygrid::loop
{
enum class DescriptorType : std::uint32_t
{
	Binary = 0,  //!< CV_8U rows, Hamming distance
	Float = 1    //!< CV_32F rows, L2 distance
};

struct VocabularyOptions : public core::FieldTableOptions<VocabularyOptions>
{
	/** Branching factor k: children per node (Default: 10) */
	int branching{10};
	/** Depth L: levels below the root; at most k^L words (Default: 4) */
	int levels{4};
	/** Lloyd iterations per k-means after k-means++ seeding (Default: 10) */
	int maxIterations{10};
	/** Seed of the k-means++ random draws (Default: 1) */
	std::uint64_t seed{1};
	/** Worker threads for training; 0 = hardware concurrency. The tree does not depend on it (Default: 0) */
	int threads{0};

	/** The INI keys branching, levels, max_iterations, seed, threads, with description and rule
	 * (core/OptionFields.h). */
	core::OptionFields fields();
	/** Throws std::invalid_argument("[section] key = value (must be ...)") on a bad value, and
	 * for a tree of more than 4e9 words (word ids are 32-bit). */
	void validate(const std::string& section = "vocabulary") const;
};

class Vocabulary
{
   public:
	/** Called during training with (descriptors clustered so far, total). May be empty. */
	using Progress = std::function<void(std::size_t done, std::size_t total)>;

	/** Version written by save(); load() throws on any other. */
	static constexpr std::uint32_t kFileVersion = 1;

	Vocabulary() = default;

	/** Trains on the descriptors of N images (one cv::Mat per image, all of the same type and
	 * width). Throws std::invalid_argument on no descriptors, mixed types or invalid options. */
	static Vocabulary train(
		const std::vector<cv::Mat>& imageDescriptors, const VocabularyOptions& opts = {},
		const Progress& progress = {});

	/** TF-IDF BoW vector of one image's descriptors (word weights sum to 1). */
	BowVector transform(const cv::Mat& descriptors) const;
	/** Same, and fills the direct index: node at depth `directLevel` (1 = children of the root,
	 * clamped to the tree depth) -> indices of the descriptor rows under it. */
	BowVector transform(const cv::Mat& descriptors, FeatureVector& direct, int directLevel) const;

	/** Word of one descriptor (a 1-row cv::Mat of the vocabulary's type and width). */
	WordId wordOf(const cv::Mat& descriptor) const;

	/** L1 score of two BoW vectors (see l1Score()). */
	double score(const BowVector& a, const BowVector& b) const { return l1Score(a, b); }

	bool empty() const { return m_words.empty(); }
	std::size_t numWords() const { return m_words.size(); }
	std::size_t numNodes() const { return m_nodes.size(); }
	int branching() const { return m_branching; }
	int levels() const { return m_levels; }
	DescriptorType descriptorType() const { return m_type; }
	/** Bytes (binary) or floats (float) per descriptor. */
	int descriptorCols() const { return m_cols; }
	std::size_t trainingImages() const { return m_trainingImages; }
	double idf(WordId w) const { return m_idf.at(w); }
	/** Node id of a word (its leaf). */
	NodeId wordNode(WordId w) const { return m_words.at(w); }
	/** Depth of a node (root: 0). */
	int nodeDepth(NodeId n) const { return m_nodes.at(n).depth; }

	/** One paragraph: type, k, L, words, nodes, training images. */
	std::string describe() const;

	/** Compact little-endian binary: magic "KGVOCAB\0", version, header, nodes, centres, idf. */
	void save(const std::string& path) const;
	void save(std::ostream& os) const;
	/** Throws std::runtime_error on a wrong magic, an unknown version, a truncated or
	 * inconsistent file. */
	static Vocabulary load(const std::string& path);
	static Vocabulary load(std::istream& is);

	/** Internal tree node (flattened, children contiguous). */
	struct Node
	{
		std::uint32_t firstChild{0};
		std::uint32_t numChildren{0};
		std::int32_t word{-1};  //!< word id for leaves, -1 otherwise
		std::int32_t depth{0};
	};

   private:
	friend class VocabularyBuilder;
	template <class Metric>
	NodeId descend(const Metric& m, const uchar* d, int directLevel, NodeId* directNode) const;
	void checkDescriptors(const cv::Mat& d) const;

	DescriptorType m_type{DescriptorType::Binary};
	int m_cols{0};
	int m_branching{0}, m_levels{0};
	std::size_t m_trainingImages{0};
	std::vector<Node> m_nodes;
	cv::Mat m_centres;  //!< one row per node (root row unused)
	std::vector<NodeId> m_words;  //!< word -> leaf node
	std::vector<double> m_idf;    //!< word -> idf weight
};

}  // namespace keygrid::loop

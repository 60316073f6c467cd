/** \file Vocabulary.cpp
 * Options, tree descent (transform) and description of the vocabulary tree.
 */
#include "DescriptorMetric.h"

#include <keygrid/loop/Vocabulary.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace keygrid::loop
{
core::OptionFields VocabularyOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f(34);
	f.add("branching", branching, "k: children per node", R::atLeast(2));
	f.add("levels", levels, "L: depth of the tree (k^L words at most)", R::atLeast(1));
	f.add("max_iterations", maxIterations, "Lloyd iterations per k-means", R::atLeast(1));
	f.add("seed", seed, "k-means++ seed");
	f.add("threads", threads, "training threads (0: all cores)", R::atLeast(0));
	return f;
}

void VocabularyOptions::validate(const std::string& section) const
{
	core::validateFields(*this, section);
	// Word and node ids are 32-bit.
	constexpr double kMaxWords = 4.0e9;
	double words = 1;
	for (int l = 0; l < levels && words <= kMaxWords; ++l) words *= branching;
	if (words > kMaxWords)
		throw std::invalid_argument(
			"[" + section + "] branching = " + std::to_string(branching) + ", levels = " + std::to_string(levels) +
			" (branching^levels words must be at most 4e9)");
}

void Vocabulary::checkDescriptors(const cv::Mat& d) const
{
	if (empty()) throw std::logic_error("Vocabulary: empty (train or load it first)");
	if (d.empty()) return;
	const int want = m_type == DescriptorType::Binary ? CV_8U : CV_32F;
	if (d.type() != want || d.cols != m_cols)
	{
		std::ostringstream os;
		os << "Vocabulary: descriptors of type " << d.type() << " with " << d.cols
		   << " columns do not match the vocabulary (" << (m_type == DescriptorType::Binary ? "binary" : "float")
		   << ", " << m_cols << " columns)";
		throw std::invalid_argument(os.str());
	}
}

template <class Metric>
NodeId Vocabulary::descend(const Metric& m, const uchar* d, int directLevel, NodeId* directNode) const
{
	NodeId cur = 0;
	while (m_nodes[cur].numChildren > 0)
	{
		const Node& n = m_nodes[cur];
		NodeId best = n.firstChild;
		double bestD = m.distance(d, m_centres.ptr(static_cast<int>(best)));
		for (std::uint32_t c = 1; c < n.numChildren; ++c)
		{
			const NodeId id = n.firstChild + c;
			const double dist = m.distance(d, m_centres.ptr(static_cast<int>(id)));
			if (dist < bestD)
			{
				bestD = dist;
				best = id;
			}
		}
		cur = best;
		if (directNode && m_nodes[cur].depth <= directLevel) *directNode = cur;
	}
	return cur;
}

BowVector Vocabulary::transform(const cv::Mat& descriptors, FeatureVector& direct, int directLevel) const
{
	checkDescriptors(descriptors);
	direct.clear();
	BowVector v;
	v.reserve(static_cast<std::size_t>(descriptors.rows));
	const int lvl = std::max(1, directLevel);
	for (int r = 0; r < descriptors.rows; ++r)
	{
		NodeId dn = 0;
		const NodeId leaf = m_type == DescriptorType::Binary
								? descend(detail::BinaryMetric{m_cols}, descriptors.ptr(r), lvl, &dn)
								: descend(detail::FloatMetric{m_cols}, descriptors.ptr(r), lvl, &dn);
		const auto w = static_cast<WordId>(m_nodes[leaf].word);
		// TF-IDF: each occurrence adds idf; after L1 normalisation the weight is
		// (n_wd / n_d) * idf_w up to the common factor, i.e. term frequency times idf.
		v.push_back(BowEntry{w, m_idf[w]});
		direct[dn].push_back(r);
	}
	canonicalise(v);
	// Words seen in every training image have idf 0: drop them (they carry no information).
	v.erase(std::remove_if(v.begin(), v.end(), [](const BowEntry& e) { return e.weight <= 0; }), v.end());
	normaliseL1(v);
	return v;
}

BowVector Vocabulary::transform(const cv::Mat& descriptors) const
{
	checkDescriptors(descriptors);
	BowVector v;
	v.reserve(static_cast<std::size_t>(descriptors.rows));
	for (int r = 0; r < descriptors.rows; ++r)
	{
		const NodeId leaf = m_type == DescriptorType::Binary
								? descend(detail::BinaryMetric{m_cols}, descriptors.ptr(r), 0, nullptr)
								: descend(detail::FloatMetric{m_cols}, descriptors.ptr(r), 0, nullptr);
		const auto w = static_cast<WordId>(m_nodes[leaf].word);
		v.push_back(BowEntry{w, m_idf[w]});
	}
	canonicalise(v);
	v.erase(std::remove_if(v.begin(), v.end(), [](const BowEntry& e) { return e.weight <= 0; }), v.end());
	normaliseL1(v);
	return v;
}

WordId Vocabulary::wordOf(const cv::Mat& descriptor) const
{
	checkDescriptors(descriptor);
	if (descriptor.rows != 1) throw std::invalid_argument("Vocabulary::wordOf: expects one descriptor row");
	const NodeId leaf = m_type == DescriptorType::Binary
							? descend(detail::BinaryMetric{m_cols}, descriptor.ptr(0), 0, nullptr)
							: descend(detail::FloatMetric{m_cols}, descriptor.ptr(0), 0, nullptr);
	return static_cast<WordId>(m_nodes[leaf].word);
}

std::string Vocabulary::describe() const
{
	std::ostringstream os;
	if (empty()) return "empty vocabulary";
	int maxDepth = 0;
	for (const auto& n : m_nodes) maxDepth = std::max(maxDepth, static_cast<int>(n.depth));
	os << (m_type == DescriptorType::Binary ? "binary" : "float") << " descriptors of " << m_cols
	   << (m_type == DescriptorType::Binary ? " bytes" : " floats") << ", k = " << m_branching << ", L = " << m_levels
	   << " (deepest leaf at " << maxDepth << "), " << numWords() << " words, " << numNodes() << " nodes, "
	   << m_trainingImages << " training images";
	return os.str();
}

}  // namespace keygrid::loop

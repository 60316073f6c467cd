#pragma once
/** \file BowVector.h
 * Bag-of-words vectors and the L1 similarity score of Nister & Stewenius (2006).
 */
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace keygrid::loop
{
/** Index of a leaf of the vocabulary tree (a "visual word"). */
using WordId = std::uint32_t;
/** Index of any node of the vocabulary tree (root = 0). */
using NodeId = std::uint32_t;
/** Keyframe identifier as the caller numbers them (the frontend's KeyFrame ids). */
using KeyFrameId = std::uint64_t;

/** One entry of a BowVector: a word and its TF-IDF weight. */
struct BowEntry
{
	WordId word{0};
	double weight{0};
};

/** Sparse word histogram, sorted by word id, no duplicate words. After
 * Vocabulary::transform() the weights are TF-IDF and sum to 1 (L1-normalised). */
using BowVector = std::vector<BowEntry>;

/** Direct index: node at a chosen tree level -> indices of the features (descriptor rows) that
 * passed through it. Matching two frames then only compares features under the same node. */
using FeatureVector = std::map<NodeId, std::vector<int>>;

/** Sorts by word and merges duplicates (sums their weights). */
void canonicalise(BowVector& v);

/** Divides every weight by the L1 norm (sum of |w|); no-op on an all-zero vector. */
void normaliseL1(BowVector& v);

/** L1 score s(v1, v2) = 1 - 0.5 | v1/|v1| - v2/|v2| |_1, in [0, 1] (1: identical).
 * Evaluated over the common words only, using |a - b| = |a| + |b| - (|a| + |b| - |a - b|):
 * for L1-normalised inputs s = 0.5 * sum_common (|a_i| + |b_i| - |a_i - b_i|).
 * Inputs need not be normalised (they are normalised on the fly); both must be canonical. */
double l1Score(const BowVector& v1, const BowVector& v2);

/** Sum of |w|. */
double l1Norm(const BowVector& v);

}  // namespace keygrid::loop

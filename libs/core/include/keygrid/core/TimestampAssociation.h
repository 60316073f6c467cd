#pragma once
/** \file TimestampAssociation.h
 * Nearest-timestamp association of two time series (TUM associate.py's rule).
 */
#include <cstddef>
#include <utility>
#include <vector>

namespace keygrid::core
{
/** Pairs (i, j) with |a[i] - b[j]| <= maxDt, each index used at most once, chosen greedily by
 * increasing |dt| (the rule of TUM's associate.py). Inputs need not be sorted; the result is
 * sorted by a[i]. */
std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(
	const std::vector<double>& a, const std::vector<double>& b, double maxDt);

}  // namespace keygrid::core

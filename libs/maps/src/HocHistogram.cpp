/** \file HocHistogram.cpp
 * HOC counts, weights and options.
 */
#include "detail/Grid3DConfig.h"

#include <keygrid/maps/HocGeometry.h>
#include <keygrid/maps/HocHistogram.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
double HocOptions::weight(int n) const { return 1.0 / (1.0 + std::exp(-sigmoidGain * (n - sigmoidOffset))); }

void HocOptions::validate() const
{
	HocGeometry(radii, subdivisions);  // throws on bad radii / subdivisions
	detail::require(sigmoidGain > 0, "sigmoid_gain", sigmoidGain, "> 0");
	detail::require(selectThreshold >= 0 && selectThreshold < 1, "select_threshold", selectThreshold, "in [0, 1)");
	detail::require(pruneThreshold >= 0 && pruneThreshold < 1, "prune_threshold", pruneThreshold, "in [0, 1)");
	detail::require(countLimit >= 1 && countLimit <= 30000, "count_limit", countLimit, "in [1, 30000]");
	detail::require(initialCount >= 1 && initialCount <= countLimit, "initial_count", initialCount, "in [1, count_limit]");
	detail::require(occlusionToleranceAbs >= 0, "occlusion_tolerance_abs", occlusionToleranceAbs, ">= 0 m");
	detail::require(occlusionToleranceRel >= 0, "occlusion_tolerance_rel", occlusionToleranceRel, ">= 0");
	detail::require(visibleDepthMin >= 0, "visible_depth_min", visibleDepthMin, ">= 0 m");
	detail::require(visibleDepthMax > visibleDepthMin, "visible_depth_max", visibleDepthMax, "> visible_depth_min");
}

void HocOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	enabled = detail::readBool(c, s, "enabled", enabled);
	const std::string r = c.read_string(s, "radii", "", false);
	if (!r.empty())
	{
		std::vector<double> v;
		std::istringstream is(r);
		std::string tok;
		while (is >> tok)
		{
			double x = 0;
			if (!core::parseTrimmedDouble(tok, x)) throw std::invalid_argument("[" + s + "] radii = '" + r + "': '" + tok + "' is not a number");
			v.push_back(x);
		}
		radii = v;
	}
	const double sub = detail::readNumber(c, s, "subdivisions", subdivisions);
	detail::require(sub == std::floor(sub), "[" + s + "] subdivisions", sub, "an integer");
	subdivisions = static_cast<int>(sub);
	sigmoidGain = detail::readNumber(c, s, "sigmoid_gain", sigmoidGain);
	sigmoidOffset = detail::readNumber(c, s, "sigmoid_offset", sigmoidOffset);
	selectThreshold = detail::readNumber(c, s, "select_threshold", selectThreshold);
	pruneThreshold = detail::readNumber(c, s, "prune_threshold", pruneThreshold);
	const double lim = detail::readNumber(c, s, "count_limit", countLimit);
	detail::require(lim == std::floor(lim) && lim >= 1 && lim <= 30000, "[" + s + "] count_limit", lim, "an integer in [1, 30000]");
	countLimit = static_cast<int>(lim);
	const double init = detail::readNumber(c, s, "initial_count", initialCount);
	detail::require(init == std::floor(init) && init >= 1 && init <= 30000, "[" + s + "] initial_count", init, "an integer >= 1");
	initialCount = static_cast<int>(init);
	occlusionToleranceAbs = detail::readNumber(c, s, "occlusion_tolerance_abs", occlusionToleranceAbs);
	occlusionToleranceRel = detail::readNumber(c, s, "occlusion_tolerance_rel", occlusionToleranceRel);
	visibleDepthMin = detail::readNumber(c, s, "visible_depth_min", visibleDepthMin);
	visibleDepthMax = detail::readNumber(c, s, "visible_depth_max", visibleDepthMax);
	decrementNeedsKeypoint = detail::readBool(c, s, "decrement_needs_keypoint", decrementNeedsKeypoint);
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void HocOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	std::ostringstream r;
	for (std::size_t i = 0; i < radii.size(); i++) r << (i ? " " : "") << radii[i];
	c.write(s, "enabled", enabled ? "true" : "false", 30, 40, "use the HOC in the frontend (false: standard system)");
	c.write(s, "radii", r.str(), 30, 40, "shell radii [m], increasing");
	c.write(s, "subdivisions", subdivisions, 30, 40, "icosahedron subdivisions: 20 * 4^s faces per shell");
	c.write(s, "sigmoid_gain", sigmoidGain, 30, 40, "bin weight p(n) = 1/(1+exp(-gain*(n-offset)))");
	c.write(s, "sigmoid_offset", sigmoidOffset, 30, 40, "see sigmoid_gain");
	c.write(s, "select_threshold", selectThreshold, 30, 40, "match a point from bin b only while p(n_b) > this");
	c.write(s, "prune_threshold", pruneThreshold, 30, 40, "remove a point when max_b p(n_b) < this");
	c.write(s, "count_limit", countLimit, 30, 40, "|n| is clamped to this");
	c.write(s, "initial_count", initialCount, 30, 40, "n of a new point in the bin of each keyframe observing it");
	c.write(s, "occlusion_tolerance_abs", occlusionToleranceAbs, 30, 40, "[m] depth closer than predicted by more than abs+rel*d = occluded");
	c.write(s, "occlusion_tolerance_rel", occlusionToleranceRel, 30, 40, "see occlusion_tolerance_abs");
	c.write(s, "visible_depth_min", visibleDepthMin, 30, 40, "[m] points nearer than this are not expected to be seen");
	c.write(s, "visible_depth_max", visibleDepthMax, 30, 40, "[m] points farther than this are not expected to be seen");
	c.write(s, "decrement_needs_keypoint", decrementNeedsKeypoint ? "true" : "false", 30, 40,
			"count a miss only when a keypoint was detected in the point's search window");
}

void HocHistogram::add(int bin, int delta, int limit, int numBins)
{
	if (bin < 0 || bin >= numBins) throw std::out_of_range("HOC bin " + std::to_string(bin) + " outside [0, " + std::to_string(numBins) + ")");
	if (m_n.empty()) m_n.assign(static_cast<std::size_t>(numBins), 0);
	auto& n = m_n[static_cast<std::size_t>(bin)];
	n = static_cast<std::int16_t>(std::clamp(n + delta, -limit, limit));
}

int HocHistogram::maxCount() const
{
	if (m_n.empty()) return 0;
	return *std::max_element(m_n.begin(), m_n.end());
}

}  // namespace keygrid::maps

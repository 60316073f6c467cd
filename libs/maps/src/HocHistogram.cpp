/** \file HocHistogram.cpp
 * HOC counts, weights and options.
 */
#include <keygrid/core/ConfigReading.h>
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

core::OptionFields HocOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("enabled", enabled, "use the HOC in the frontend (false: standard system)");
	f.addCustom(
		"radii",
		{[this](const std::string& text) {
			 std::vector<double> v;
			 std::istringstream is(text);
			 for (std::string tok; is >> tok;)
			 {
				 double x = 0;
				 if (!core::parseTrimmedDouble(tok, x)) throw std::invalid_argument("'" + tok + "' is not a number");
				 v.push_back(x);
			 }
			 radii = v;
		 },
		 [this] {
			 std::ostringstream r;
			 for (std::size_t i = 0; i < radii.size(); i++) r << (i ? " " : "") << radii[i];
			 return r.str();
		 }},
		"shell radii [m], increasing");
	f.add("subdivisions", subdivisions, "icosahedron subdivisions: 20 * 4^s faces per shell", R::inRange(0, 3));
	f.add("sigmoid_gain", sigmoidGain, "bin weight p(n) = 1/(1+exp(-gain*(n-offset)))", R::positive());
	f.add("sigmoid_offset", sigmoidOffset, "offset of that sigmoid [observations]");
	f.add("select_threshold", selectThreshold, "match a point from bin b only while p(n_b) > this", R::fromBelow(0, 1));
	f.add("prune_threshold", pruneThreshold, "remove a point when max_b p(n_b) < this", R::fromBelow(0, 1));
	f.add("count_limit", countLimit, "|n| is clamped to this", R::inRange(1, 30000));
	f.add("initial_count", initialCount, "n of a new point in the bin of each keyframe observing it (<= count_limit)", R::inRange(1, 30000));
	f.add("occlusion_tolerance_abs", occlusionToleranceAbs, "[m] depth closer than predicted by more than abs+rel*d = occluded", R::atLeast(0));
	f.add("occlusion_tolerance_rel", occlusionToleranceRel, "relative part of that tolerance (x depth)", R::atLeast(0));
	f.add("visible_depth_min", visibleDepthMin, "[m] points nearer than this are not expected to be seen", R::atLeast(0));
	f.add("visible_depth_max", visibleDepthMax, "[m] points farther than this are not expected to be seen (> visible_depth_min)");
	f.add("decrement_needs_keypoint", decrementNeedsKeypoint, "count a miss only when a keypoint was detected in the point's search window");
	return f;
}

void HocOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	try
	{
		HocGeometry(radii, subdivisions);  // throws naming the radius that is not increasing
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
	if (initialCount > countLimit)
		throw std::invalid_argument("[" + s + "] initial_count = " + std::to_string(initialCount) + " (must be <= count_limit = " + std::to_string(countLimit) + ")");
	if (!(visibleDepthMax > visibleDepthMin))
		throw std::invalid_argument(
			"[" + s + "] visible_depth_max = " + std::to_string(visibleDepthMax) + " (must be > visible_depth_min = " + std::to_string(visibleDepthMin) + ")");
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

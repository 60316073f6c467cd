// The relocalization acceptance share (TrackerOptions.h, requiredRelocalizationShare): the fixed
// relocalization_min_inlier_ratio, lowered to relocalization_share_factor x the median share
// that normal tracking matched recently, never raised.
#include <keygrid/sfm/TrackerOptions.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <utility>

using keygrid::sfm::requiredRelocalizationShare;
using keygrid::sfm::TrackerOptions;

TEST(TrackerOptions, RelocalizationShareFollowsTheRecentMedianBelowTheFixedRatio)
{
	TrackerOptions o;
	ASSERT_DOUBLE_EQ(o.relocalizationMinInlierRatio, 0.25);
	ASSERT_DOUBLE_EQ(o.relocalizationShareFactor, 0.6);
	EXPECT_DOUBLE_EQ(requiredRelocalizationShare(o, {}), 0.25);  // nothing tracked yet
	// Synthetic scenes: median 0.45 -> 0.27, capped at the fixed 0.25.
	EXPECT_DOUBLE_EQ(requiredRelocalizationShare(o, {0.5, 0.45, 0.40}), 0.25);
	// fr1_rpy with SIFT: median 0.20 (odd count: the middle value) -> 0.12.
	EXPECT_NEAR(requiredRelocalizationShare(o, {0.31, 0.10, 0.20, 0.15, 0.25}), 0.6 * 0.20, 1e-12);
	// Even count: the upper middle value (nth_element at n / 2).
	EXPECT_NEAR(requiredRelocalizationShare(o, {0.30, 0.10, 0.20, 0.15}), 0.6 * 0.20, 1e-12);
	o.relocalizationShareFactor = 0;  // fixed share
	EXPECT_DOUBLE_EQ(requiredRelocalizationShare(o, {0.30, 0.10, 0.20, 0.15}), 0.25);
}

TEST(TrackerOptions, RelocalizationShareFactorIsReadAndChecked)
{
	mrpt::config::CConfigFileMemory c;
	c.write("tracker", "relocalization_share_factor", 0.4);
	TrackerOptions o;
	o.loadFromConfigFile(c, "tracker");
	EXPECT_DOUBLE_EQ(o.relocalizationShareFactor, 0.4);
	c.write("tracker", "relocalization_share_factor", 1.5);
	EXPECT_THROW(o.loadFromConfigFile(c, "tracker"), std::invalid_argument);
}

TEST(TrackerOptions, AnchoredRefinementKeysAreReadAndChecked)
{
	mrpt::config::CConfigFileMemory c;
	c.write("tracker", "anchor_min_keyframes", 0);
	c.write("tracker", "anchor_chi2_factor", 4.0);
	c.write("tracker", "anchor_min_count", 50);
	TrackerOptions o;
	o.loadFromConfigFile(c, "tracker");
	EXPECT_EQ(o.anchorMinKeyFrames, 0);  // 0 = off
	EXPECT_DOUBLE_EQ(o.anchorChi2Factor, 4.0);
	EXPECT_EQ(o.anchorMinCount, 50);
	for (const auto& [key, bad] : {std::pair<const char*, const char*>{"anchor_min_keyframes", "-1"}, {"anchor_chi2_factor", "0.5"}, {"anchor_min_count", "0"}})
	{
		mrpt::config::CConfigFileMemory b;
		b.write("tracker", key, std::string(bad));
		TrackerOptions t;
		EXPECT_THROW(t.loadFromConfigFile(b, "tracker"), std::invalid_argument) << key << " = " << bad;
	}
}

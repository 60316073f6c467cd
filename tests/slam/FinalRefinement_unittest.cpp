#include <keygrid/slam/FinalRefinement.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace keygrid;
using mrpt::poses::CPose3D;

TEST(FinalRefinement, SeedsAreBothEndsOfEveryLoopNewestFirstThenTheNewestKeyFrame)
{
	sfm::SparseMap map;
	for (int i = 0; i < 5; i++) map.addKeyFrame(sfm::KeyFrame{});
	std::vector<loop::LoopClosureEvent> loops(2);
	loops[0].keyframe = 3;
	loops[0].loopKeyFrame = 0;
	loops[1].keyframe = 4;
	loops[1].loopKeyFrame = 1;
	EXPECT_EQ(slam::finalWindowSeeds(loops, map), (std::vector<sfm::KeyFrameId>{4, 1, 3, 0, 4}));
	EXPECT_EQ(slam::finalWindowSeeds({}, map), (std::vector<sfm::KeyFrameId>{4}));
}

TEST(FinalRefinement, DisplacementCountsTheCentreAndThePointAheadOfTheCamera)
{
	const std::map<sfm::KeyFrameId, CPose3D> before{{1, CPose3D()}, {2, CPose3D()}};
	// Keyframe 1 moves 2 cm sideways; keyframe 2 turns 0.01 rad about its y axis (pitch), which
	// moves the point 4 m ahead on its optical (z) axis by 2 x 4 x sin(0.005) m.
	const std::map<sfm::KeyFrameId, CPose3D> after{{1, CPose3D(0.02, 0, 0, 0, 0, 0)}, {2, CPose3D(0, 0, 0, 0, 0.01, 0)}};
	EXPECT_NEAR(slam::largestDisplacement(before, after, 4.0), 8 * std::sin(0.005), 1e-9);
	EXPECT_NEAR(slam::largestDisplacement(before, after, 0.0), 0.02, 1e-12);
	// Keyframes absent from `after` (erased) do not count.
	EXPECT_EQ(slam::largestDisplacement(before, {{7, CPose3D(1, 0, 0, 0, 0, 0)}}, 4.0), 0.0);
}

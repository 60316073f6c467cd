// searchForInitialization (InitialMatcher.h) on synthetic features (SyntheticFeatures.h): every
// point has its own random descriptor, so the true correspondences are known and any other pair
// is ~128 bits apart, far above the match threshold.
#include <keygrid/sfm/InitialMatcher.h>

#include "SyntheticFeatures.h"

#include <gtest/gtest.h>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
/** `n` points over the first camera's image, 20 px inside its borders, at depths in [2, 5] m. */
test::SyntheticPoints pointsInView(const core::RgbdCamera& cam, std::mt19937& rng, int n)
{
	return test::pointsInView(cam, rng, n, 20, 2.0, 5.0);
}

/** The keypoints of `f` moved by (du, dv) pixels that stay inside the image (grid rebuilt);
 * `source` receives the index in `f` of each. */
sfm::FrameFeatures shifted(const sfm::FrameFeatures& f, float du, float dv, std::vector<int>& source)
{
	sfm::FrameFeatures out = f;
	out.keypoints.clear();
	out.undistorted.clear();
	out.depth.clear();
	source.clear();
	cv::Mat rows;
	for (std::size_t i = 0; i < f.size(); i++)
	{
		const cv::Point2f p = f.undistorted[i] + cv::Point2f(du, dv);
		if (p.x < 0 || p.y < 0 || p.x >= f.camera.width || p.y >= f.camera.height) continue;
		auto k = f.keypoints[i];
		k.pt = p;
		out.keypoints.push_back(k);
		out.undistorted.push_back(p);
		out.depth.push_back(f.depth[i]);
		rows.push_back(f.descriptors.row(static_cast<int>(i)));
		source.push_back(static_cast<int>(i));
	}
	out.descriptors = rows;
	out.buildGrid();
	return out;
}
}  // namespace

TEST(InitialMatcher, FindsEveryTrueCorrespondenceAndUpdatesThePrediction)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(3);
	const auto world = pointsInView(cam, rng, 400);
	std::vector<int> refPoint, curPoint;
	const auto ref = test::observePoints(world, CPose3D(), cam, {}, rng, &refPoint);
	const auto cur = test::observePoints(world, CPose3D(0.1, 0.02, 0.05, 0.03, 0.01, 0.0), cam, {}, rng, &curPoint);
	std::vector<cv::Point2f> predicted = ref.undistorted;
	std::vector<int> refToCur;
	const int n = sfm::searchForInitialization(ref, cur, predicted, sfm::InitialMatchOptions(), refToCur);
	// Every point seen in both views: all of them but those the motion took out of the image.
	int common = 0;
	for (int p : refPoint) common += std::count(curPoint.begin(), curPoint.end(), p) > 0;
	EXPECT_EQ(n, common);
	for (std::size_t i = 0; i < ref.size(); i++)
	{
		if (refToCur[i] < 0) continue;
		EXPECT_EQ(curPoint[refToCur[i]], refPoint[i]) << "reference keypoint " << i;
		EXPECT_EQ(predicted[i], cur.undistorted[refToCur[i]]);
	}
}

TEST(InitialMatcher, SearchesOnlyInsideTheWindow)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(4);
	const auto world = pointsInView(cam, rng, 300);
	const auto ref = test::observePoints(world, CPose3D(), cam, {}, rng);
	// Every keypoint 150 px to the right (those leaving the image dropped).
	std::vector<int> source;
	const auto cur = shifted(ref, 150.f, 0.f, source);
	ASSERT_GT(cur.size(), 100u);
	std::vector<int> refToCur;
	sfm::InitialMatchOptions o;
	auto predicted = ref.undistorted;
	EXPECT_EQ(sfm::searchForInitialization(ref, cur, predicted, o, refToCur), 0);
	o.windowPx = 160.f;
	predicted = ref.undistorted;
	EXPECT_EQ(sfm::searchForInitialization(ref, cur, predicted, o, refToCur), static_cast<int>(cur.size()));
	for (std::size_t i = 0; i < ref.size(); i++)
		if (refToCur[i] >= 0) { EXPECT_EQ(source[refToCur[i]], static_cast<int>(i)); }
}

TEST(InitialMatcher, DropsMatchesWithAnInconsistentOrientationChange)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(5);
	const auto world = pointsInView(cam, rng, 200);
	auto ref = test::observePoints(world, CPose3D(), cam, {}, rng);
	auto cur = ref;
	// The image turns the keypoints by 20 deg; 8 of them (true matches by descriptor) claim
	// turns of their own, each in another of the 30 bins: a bin of one is below a tenth of the
	// consistent bin and goes.
	for (auto& k : ref.keypoints) k.angle = 30.f;
	for (auto& k : cur.keypoints) k.angle = 10.f;
	for (int j = 0; j < 8; j++) cur.keypoints[j].angle = 30.f - 20.f - 36.f * static_cast<float>(j + 1);
	for (auto& k : cur.keypoints)
		if (k.angle < 0) k.angle += 360.f;
	std::vector<int> refToCur;
	auto predicted = ref.undistorted;
	sfm::InitialMatchOptions o;
	EXPECT_EQ(sfm::searchForInitialization(ref, cur, predicted, o, refToCur), static_cast<int>(ref.size()) - 8);
	for (int j = 0; j < 8; j++) EXPECT_EQ(refToCur[j], -1);
	o.checkOrientation = false;
	predicted = ref.undistorted;
	EXPECT_EQ(sfm::searchForInitialization(ref, cur, predicted, o, refToCur), static_cast<int>(ref.size()));
}

TEST(InitialMatcher, ThrowsOnAPredictionOfAnotherSize)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(6);
	const auto world = pointsInView(cam, rng, 50);
	const auto ref = test::observePoints(world, CPose3D(), cam, {}, rng);
	std::vector<cv::Point2f> predicted(ref.size() - 1);
	std::vector<int> refToCur;
	EXPECT_THROW(sfm::searchForInitialization(ref, ref, predicted, {}, refToCur), std::invalid_argument);
}

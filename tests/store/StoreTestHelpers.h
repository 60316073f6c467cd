#pragma once
/** \file StoreTestHelpers.h
 * Exact comparisons of the store's records (gtest assertions).
 */
#include <gtest/gtest.h>
#include <keygrid/store/SessionRecords.h>

#include "TestChecks.h"

namespace keygrid::test
{
inline void expectSamePose(const mrpt::poses::CPose3D& a, const mrpt::poses::CPose3D& b)
{
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) EXPECT_EQ(a.getRotationMatrix()(r, c), b.getRotationMatrix()(r, c));
	EXPECT_EQ(a.x(), b.x());
	EXPECT_EQ(a.y(), b.y());
	EXPECT_EQ(a.z(), b.z());
}

inline void expectSameCamera(const core::RgbdCamera& a, const core::RgbdCamera& b)
{
	EXPECT_EQ(a.name, b.name);
	EXPECT_EQ(a.width, b.width);
	EXPECT_EQ(a.height, b.height);
	EXPECT_EQ(a.fx, b.fx);
	EXPECT_EQ(a.fy, b.fy);
	EXPECT_EQ(a.cx, b.cx);
	EXPECT_EQ(a.cy, b.cy);
	EXPECT_EQ(a.dist, b.dist);
	EXPECT_EQ(a.depthUnits, b.depthUnits);
}

inline void expectSameKeyFrame(const store::KeyFrameRecord& a, const store::KeyFrameRecord& b)
{
	SCOPED_TRACE("keyframe " + std::to_string(a.id));
	EXPECT_EQ(a.id, b.id);
	EXPECT_EQ(a.frameIndex, b.frameIndex);
	EXPECT_EQ(a.timestamp, b.timestamp);
	expectSamePose(a.T_world_cam, b.T_world_cam);
	EXPECT_EQ(a.hasParent, b.hasParent);
	EXPECT_EQ(a.parent, b.parent);
	expectSameCamera(a.camera, b.camera);
	ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
	for (std::size_t i = 0; i < a.keypoints.size(); i++)
	{
		const auto &p = a.keypoints[i], &q = b.keypoints[i];
		EXPECT_TRUE(p.pt == q.pt && p.size == q.size && p.angle == q.angle && p.response == q.response &&
					p.octave == q.octave && p.class_id == q.class_id)
			<< "keypoint " << i;
	}
	EXPECT_EQ(a.undistorted, b.undistorted);
	EXPECT_EQ(a.keypointDepth, b.keypointDepth);
	EXPECT_TRUE(sameBits(a.descriptors, b.descriptors));
	EXPECT_EQ(a.levelScale, b.levelScale);
	EXPECT_EQ(a.numLevels, b.numLevels);
	EXPECT_EQ(a.landmarks, b.landmarks);
	ASSERT_EQ(a.bow.size(), b.bow.size());
	for (std::size_t i = 0; i < a.bow.size(); i++)
	{
		EXPECT_EQ(a.bow[i].word, b.bow[i].word);
		EXPECT_EQ(a.bow[i].weight, b.bow[i].weight);
	}
}

inline void expectSameLandmark(const store::LandmarkRecord& a, const store::LandmarkRecord& b)
{
	SCOPED_TRACE("landmark " + std::to_string(a.id));
	EXPECT_EQ(a.id, b.id);
	EXPECT_EQ(a.p_world, b.p_world);
	EXPECT_EQ(a.normal, b.normal);
	EXPECT_TRUE(sameBits(a.descriptor, b.descriptor));
	EXPECT_EQ(a.observations, b.observations);
	EXPECT_EQ(a.minDistance, b.minDistance);
	EXPECT_EQ(a.maxDistance, b.maxDistance);
	EXPECT_EQ(a.firstKeyFrame, b.firstKeyFrame);
	EXPECT_EQ(a.visibleCount, b.visibleCount);
	EXPECT_EQ(a.foundCount, b.foundCount);
	EXPECT_EQ(a.hocCounts, b.hocCounts);
}

/** `edges` are `expected`, in the same order. */
inline void expectSameCovisibility(
	const std::vector<store::CovisibilityEdge>& edges, const std::vector<store::CovisibilityEdge>& expected)
{
	ASSERT_EQ(edges.size(), expected.size());
	for (std::size_t i = 0; i < edges.size(); i++)
	{
		SCOPED_TRACE("covisibility edge " + std::to_string(i));
		EXPECT_EQ(edges[i].a, expected[i].a);
		EXPECT_EQ(edges[i].b, expected[i].b);
		EXPECT_EQ(edges[i].weight, expected[i].weight);
	}
}

}  // namespace keygrid::test

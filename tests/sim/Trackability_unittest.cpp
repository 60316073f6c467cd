// The shipped scenes are made for visual SLAM: ORB finds many features, and features matched
// between nearby frames agree with the ground-truth motion.
#include <keygrid/sim/Simulator.h>
#include <opencv2/features2d.hpp>

#include "TestData.h"

#include <algorithm>
#include <iostream>

using namespace keygrid;

TEST(Trackability, OrbMatchesFollowTheGroundTruth)
{
	for (const char* name : {"room_loop", "corridor_loop"})
	{
		const sim::Scene scene =
			sim::Scene::loadFromFile(test::sourceDir() + "/config/sim/" + name + ".ini");
		const sim::Simulator simulator(scene, 2);
		sim::SimFrame a, b;
		simulator.frame(100, a);
		simulator.frame(103, b);  // 0.1 s apart
		auto orb = cv::ORB::create(1000);
		std::vector<cv::KeyPoint> ka, kb;
		cv::Mat da, db;
		orb->detectAndCompute(a.frame.grey, cv::noArray(), ka, da);
		orb->detectAndCompute(b.frame.grey, cv::noArray(), kb, db);
		EXPECT_GE(ka.size(), 900u) << name;
		std::vector<std::vector<cv::DMatch>> knn;
		cv::BFMatcher(cv::NORM_HAMMING).knnMatch(da, db, knn, 2);
		// Predict each matched keypoint in frame b from its depth and the true relative pose.
		const Eigen::Isometry3d T_ba = sim::Renderer::toIsometry(b.T_world_cam).inverse() *
			sim::Renderer::toIsometry(a.T_world_cam);
		const auto& c = scene.camera;
		std::vector<double> err;
		for (const auto& m : knn)
		{
			if (m.size() < 2 || m[0].distance > 0.8 * m[1].distance) continue;
			const cv::Point2f pa = ka[m[0].queryIdx].pt, pb = kb[m[0].trainIdx].pt;
			const float z = a.render.depth.at<float>(cvRound(pa.y), cvRound(pa.x));
			if (!(z > 0)) continue;
			const Eigen::Vector3d p =
				T_ba * Eigen::Vector3d(z * (pa.x - c.cx) / c.fx, z * (pa.y - c.cy) / c.fy, z);
			err.push_back(std::hypot(
				c.fx * p.x() / p.z() + c.cx - pb.x, c.fy * p.y() / p.z() + c.cy - pb.y));
		}
		ASSERT_GE(err.size(), 300u) << name;
		std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
		EXPECT_LT(err[err.size() / 2], 1.5) << name << ": median reprojection error [px]";
		const auto inliers = std::count_if(err.begin(), err.end(), [](double e) { return e < 3; });
		std::cout << name << ": " << ka.size() << " ORB keypoints, " << err.size()
				  << " ratio-test matches with depth, median error " << err[err.size() / 2]
				  << " px, " << inliers << " within 3 px\n";
		EXPECT_GT(inliers, static_cast<long>(err.size() * 8 / 10)) << name;
	}
}

#include <keygrid/sfm/PnpSolver.h>
#include <mrpt/math/CMatrixFixed.h>
#include <opencv2/calib3d.hpp>

namespace keygrid::sfm
{
PnpResult solvePnpRansac(
	const std::vector<Eigen::Vector3d>& pw, const std::vector<Eigen::Vector2d>& px,
	const PinholeIntrinsics& K, const PnpOptions& o)
{
	PnpResult res;
	if (pw.size() != px.size() || static_cast<int>(pw.size()) < std::max(4, o.minInliers)) return res;
	std::vector<cv::Point3f> obj;
	std::vector<cv::Point2f> img;
	for (std::size_t i = 0; i < pw.size(); i++)
	{
		obj.emplace_back(static_cast<float>(pw[i].x()), static_cast<float>(pw[i].y()), static_cast<float>(pw[i].z()));
		img.emplace_back(static_cast<float>(px[i].x()), static_cast<float>(px[i].y()));
	}
	const cv::Matx33d Km(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
	cv::Mat rvec, tvec;
	std::vector<int> inl;
	cv::theRNG().state = o.seed;  // OpenCV's RANSAC draws from the thread's RNG
	const bool ok = cv::solvePnPRansac(
		obj, img, Km, cv::noArray(), rvec, tvec, false, o.iterations, static_cast<float>(o.reprojectionError),
		0.999, inl, cv::SOLVEPNP_EPNP);
	if (!ok || static_cast<int>(inl.size()) < o.minInliers) return res;
	cv::Mat Rm;
	cv::Rodrigues(rvec, Rm);
	mrpt::math::CMatrixDouble33 R;
	mrpt::math::CVectorFixedDouble<3> t;
	for (int i = 0; i < 3; i++)
	{
		for (int j = 0; j < 3; j++) R(i, j) = Rm.at<double>(i, j);
		t[i] = tvec.at<double>(i);
	}
	res.T_world_cam = -mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
	res.inliers = inl;
	res.ok = true;
	return res;
}

}  // namespace keygrid::sfm

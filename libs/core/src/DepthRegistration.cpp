#include <keygrid/core/DepthRegistration.h>
#include <keygrid/core/FrameConventions.h>
#include <opencv2/calib3d.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace keygrid::core
{
bool projectWithDistortion(
	const mrpt::img::TCamera& cam, double x, double y, double z, double& u, double& v)
{
	if (!(z > 0)) return false;
	double xn = x / z, yn = y / z;
	if (cam.distortion == mrpt::img::DistortionModel::plumb_bob)
	{
		// Brown-Conrady, OpenCV order (k1 k2 p1 p2 k3).
		const double r2 = xn * xn + yn * yn;
		const double radial = 1 + r2 * (cam.k1() + r2 * (cam.k2() + r2 * cam.k3()));
		const double xd = xn * radial + 2 * cam.p1() * xn * yn + cam.p2() * (r2 + 2 * xn * xn);
		const double yd = yn * radial + cam.p1() * (r2 + 2 * yn * yn) + 2 * cam.p2() * xn * yn;
		xn = xd;
		yn = yd;
	}
	u = cam.fx() * xn + cam.cx();
	v = cam.fy() * yn + cam.cy();
	return true;
}

cv::Mat registerDepthToIntensity(
	const cv::Mat& raw, float units, const mrpt::img::TCamera& dc, const mrpt::img::TCamera& ic,
	const mrpt::poses::CPose3D& T_depth_intensity)
{
	CV_Assert(raw.type() == CV_16UC1);
	const int W = raw.cols, H = raw.rows;
	// Normalised rays of every depth pixel (undistorted once per call).
	std::vector<cv::Point2f> px;
	px.reserve(static_cast<std::size_t>(W) * H);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++) px.emplace_back(static_cast<float>(c), static_cast<float>(r));
	std::vector<cv::Point2f> rays;
	const cv::Matx33d K(dc.fx(), 0, dc.cx(), 0, dc.fy(), dc.cy(), 0, 0, 1);
	std::vector<double> D;
	if (dc.distortion == mrpt::img::DistortionModel::plumb_bob)
		D = {dc.k1(), dc.k2(), dc.p1(), dc.p2(), dc.k3()};
	cv::undistortPoints(px, rays, K, D);

	// Pose of the depth camera's optical frame seen from the intensity camera's optical frame.
	const mrpt::poses::CPose3D T_int_depthCam = (-T_depth_intensity) + T_depth_cam();
	const int IW = static_cast<int>(ic.ncols), IH = static_cast<int>(ic.nrows);
	cv::Mat out(IH, IW, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
	for (int r = 0; r < H; r++)
	{
		const auto* in = raw.ptr<uint16_t>(r);
		for (int c = 0; c < W; c++)
		{
			if (in[c] == 0) continue;
			const double d = static_cast<double>(in[c]) * units;
			const auto& ray = rays[static_cast<std::size_t>(r) * W + c];
			double x, y, z;
			T_int_depthCam.composePoint(ray.x * d, ray.y * d, d, x, y, z);
			double u, v;
			if (!projectWithDistortion(ic, x, y, z, u, v)) continue;
			const int iu = static_cast<int>(std::lround(u)), iv = static_cast<int>(std::lround(v));
			if (iu < 0 || iv < 0 || iu >= IW || iv >= IH) continue;
			float& cell = out.at<float>(iv, iu);
			if (z < cell) cell = static_cast<float>(z);
		}
	}
	cv::Mat res(IH, IW, CV_16UC1);
	for (int r = 0; r < IH; r++)
	{
		const float* in = out.ptr<float>(r);
		auto* o = res.ptr<uint16_t>(r);
		for (int c = 0; c < IW; c++)
		{
			const double q = std::isfinite(in[c]) ? std::round(in[c] / units) : 0.0;
			o[c] = q > 65535.0 ? 0 : static_cast<uint16_t>(q);
		}
	}
	return res;
}

}  // namespace keygrid::core

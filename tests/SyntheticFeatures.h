#pragma once
/** \file SyntheticFeatures.h
 * Features as an extractor would deliver them, made from known 3D points and a known camera
 * pose, for tests of tracking and loop closing against ground truth: each point projects to a
 * level-0 keypoint with its depth and its own random 256-bit descriptor (identical in every
 * view, so descriptor matching is exact and the test measures the geometry), plus Gaussian
 * pixel and depth noise. Also the accuracy to expect of a rigid alignment of such points.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/sfm/FrameFeatures.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <vector>

namespace keygrid::test
{
/** Points of a synthetic world with one descriptor each. */
struct SyntheticPoints
{
	std::vector<Eigen::Vector3d> p_world;
	cv::Mat descriptors;  //!< CV_8U, 32 bytes per point, row i for point i
};

/** n random 256-bit descriptors, one per row (CV_8U). */
inline cv::Mat randomDescriptors(int n, std::mt19937& rng)
{
	std::uniform_int_distribution<int> byte(0, 255);
	cv::Mat d(n, 32, CV_8U);
	for (int i = 0; i < n; i++)
		for (int b = 0; b < 32; b++) d.at<std::uint8_t>(i, b) = static_cast<std::uint8_t>(byte(rng));
	return d;
}

/** `n` points spread over the image of `cam` placed at the world's origin (its optical frame is
 * the world frame), at least `marginPx` pixels inside the borders, at depths uniform in
 * [minDepth, maxDepth] m. */
inline SyntheticPoints pointsInView(
	const core::RgbdCamera& cam, std::mt19937& rng, int n, double marginPx, double minDepth, double maxDepth)
{
	SyntheticPoints w;
	std::uniform_real_distribution<double> u(marginPx, cam.width - marginPx), v(marginPx, cam.height - marginPx),
		z(minDepth, maxDepth);
	for (int i = 0; i < n; i++)
	{
		const double d = z(rng);
		w.p_world.emplace_back((u(rng) - cam.cx) / cam.fx * d, (v(rng) - cam.cy) / cam.fy * d, d);
	}
	w.descriptors = randomDescriptors(n, rng);
	return w;
}

/** `n` points on the inside of a vertical cylinder about the world's y axis (radius [m],
 * heights in [-halfHeight, halfHeight]), at random azimuths: a textured wall all around. */
inline SyntheticPoints cylinderWall(std::mt19937& rng, double radius, double halfHeight, int n)
{
	SyntheticPoints w;
	std::uniform_real_distribution<double> azimuth(0, 2 * M_PI), height(-halfHeight, halfHeight);
	for (int i = 0; i < n; i++)
	{
		const double a = azimuth(rng);
		w.p_world.emplace_back(radius * std::sin(a), height(rng), radius * std::cos(a));
	}
	w.descriptors = randomDescriptors(n, rng);
	return w;
}

/** Gaussian noise of the synthetic measurements (0: exact). */
struct MeasurementNoise
{
	double pixelSigma{0};  //!< keypoint position [px]
	double depthSigma{0};  //!< depth [m]

	/** The largest standard deviation of a measured point's 3D position up to `maxDepth` [m]:
	 * depth noise along the ray, pixel noise across it (maxDepth * pixelSigma / f). */
	double pointSigma(double maxDepth, double focalLength) const { return std::max(depthSigma, maxDepth * pixelSigma / focalLength); }
};

/** The features of `points` seen by `cam` at T_world_cam: every point in front of the camera
 * that projects inside the image, in point order. pointOfKeypoint (when given) receives the
 * point index of each keypoint. */
inline sfm::FrameFeatures observePoints(
	const SyntheticPoints& points, const mrpt::poses::CPose3D& T_world_cam, const core::RgbdCamera& cam, const MeasurementNoise& noise,
	std::mt19937& rng, std::vector<int>* pointOfKeypoint = nullptr)
{
	auto gaussian = [&](double sigma) { return sigma > 0 ? std::normal_distribution<double>(0, sigma)(rng) : 0.0; };
	sfm::FrameFeatures f;
	f.camera = cam;
	f.numLevels = 8;
	for (int l = 0; l < f.numLevels; l++) f.levelScale.push_back(std::pow(1.2, l));
	std::vector<int> rows;
	for (std::size_t i = 0; i < points.p_world.size(); i++)
	{
		double x, y, z;
		T_world_cam.inverseComposePoint(points.p_world[i].x(), points.p_world[i].y(), points.p_world[i].z(), x, y, z);
		if (z < 0.1) continue;
		const double u = cam.fx * x / z + cam.cx + gaussian(noise.pixelSigma);
		const double v = cam.fy * y / z + cam.cy + gaussian(noise.pixelSigma);
		if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) continue;
		f.keypoints.emplace_back(static_cast<float>(u), static_cast<float>(v), 31.f, -1.f, 1.f, 0);
		f.undistorted.emplace_back(static_cast<float>(u), static_cast<float>(v));
		f.depth.push_back(static_cast<float>(z + gaussian(noise.depthSigma)));
		rows.push_back(static_cast<int>(i));
	}
	f.descriptors.create(static_cast<int>(rows.size()), 32, CV_8U);
	for (std::size_t k = 0; k < rows.size(); k++) points.descriptors.row(rows[k]).copyTo(f.descriptors.row(static_cast<int>(k)));
	f.buildGrid();
	if (pointOfKeypoint) *pointOfKeypoint = rows;
	return f;
}

/** A frame as a source delivers it, with blank images of the camera's size (tracking reads the
 * features; the images are only stored with keyframes). Timestamps at 30 Hz from 1 s. */
inline core::Frame blankFrame(std::size_t index, const core::RgbdCamera& cam)
{
	core::Frame f;
	f.index = index;
	f.timestamp = 1.0 + static_cast<double>(index) / 30.0;
	f.camera = cam;
	f.grey = cv::Mat::zeros(static_cast<int>(cam.height), static_cast<int>(cam.width), CV_8UC1);
	f.depth = cv::Mat::zeros(static_cast<int>(cam.height), static_cast<int>(cam.width), CV_32FC1);
	return f;
}

/** Standard deviations of the pose of a rigid alignment (the Cramer-Rao bound of 3D-3D
 * registration with isotropic noise): `n` points like `points_cam` (positions in the camera
 * frame whose pose is estimated), each measured with pointSigma [m]. Rotation about the worst
 * axis: pointSigma / sqrt(smallest eigenvalue of trace(S) I - S), S the points' scatter about
 * their centroid scaled to n points; the camera's position: pointSigma / sqrt(n), plus that
 * rotation error at the lever arm from the camera to the centroid. */
struct AlignmentSigmas
{
	double metres{0}, degrees{0};
};

inline AlignmentSigmas alignmentSigmas(const std::vector<Eigen::Vector3d>& points_cam, double pointSigma, double n)
{
	Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
	for (const auto& p : points_cam) centroid += p;
	centroid /= static_cast<double>(points_cam.size());
	Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
	for (const auto& p : points_cam) scatter += (p - centroid) * (p - centroid).transpose();
	scatter *= n / static_cast<double>(points_cam.size());
	const Eigen::Matrix3d rotationInformation = scatter.trace() * Eigen::Matrix3d::Identity() - scatter;
	const double rotationSigma =
		pointSigma / std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(rotationInformation).eigenvalues().minCoeff());
	return {std::hypot(pointSigma / std::sqrt(n), centroid.norm() * rotationSigma), rotationSigma * 180.0 / M_PI};
}

/** Rotation angle of a pose [deg]. */
inline double rotationAngleDeg(const mrpt::poses::CPose3D& T)
{
	return Eigen::AngleAxisd(Eigen::Matrix3d(T.getRotationMatrix().asEigen())).angle() * 180.0 / M_PI;
}

}  // namespace keygrid::test

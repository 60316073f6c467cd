#pragma once
/** \file RollingShutter.h
 * Rolling-shutter compensation of keypoints.
 *
 * A rolling-shutter camera (the Kinect's colour camera among them) exposes the image row by
 * row: row y of an H-row image is taken at
 *     t + tau(y),   tau(y) = (y / H - 1/2) * readout,
 * where t is the frame's timestamp (taken as the middle row) and `readout` the time between the
 * first and the last row. A camera turning at 60 deg/s with a 27 ms readout turns 1.6 deg
 * between the top and the bottom of the image, about 14 px: a global-shutter model then fits
 * a skewed image with a biased pose, and on narrow-field images that bias shows up mostly as
 * translation (the rotation/translation ambiguity).
 *
 * Over one frame the camera's motion is taken as constant: angular rate w and linear velocity
 * v, both in the camera frame at time t. The camera at t + tau relative to the camera at t is
 *     T_t_(t+tau) = (R = exp(tau [w]x), p = tau v)
 * (first order in the translation: tau v is at most a few mm). A keypoint measured at pixel
 * (u, v_px) with depth d (undistorted pinhole coordinates) sees the point
 *     P_(t+tau) = d ((u - cx) / fx, (v_px - cy) / fy, 1)
 * in the camera at t + tau, i.e. P_t = R P_(t+tau) + tau v in the camera at t. Compensation
 * replaces the measurement by the projection of P_t and its depth by P_t.z: the keypoint as
 * a global-shutter camera at t would have measured it. Without depth only the rotation is
 * applied (to the bearing), which is exact for distant points.
 *
 * The rates come from the trajectory: the relative pose between two frames divided by their
 * time difference (ratesFromRelativePose).
 */
#include <keygrid/sfm/FrameFeatures.h>
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <vector>

namespace keygrid::sfm
{
/** Camera motion rates, in the camera frame at the frame's reference time. */
struct CameraRates
{
	/** Angular rate [rad/s] */
	Eigen::Vector3d omega{Eigen::Vector3d::Zero()};
	/** Linear velocity [m/s] */
	Eigen::Vector3d velocity{Eigen::Vector3d::Zero()};
};

/** Constant rates that move a camera by T_a_b (pose of b in a) in dt seconds (dt > 0). */
CameraRates ratesFromRelativePose(const mrpt::poses::CPose3D& T_a_b, double dt);

/** Capture time of raw image row y relative to the frame timestamp [s]. */
inline double rowTimeOffset(double y, double imageHeight, double readout) { return (y / imageHeight - 0.5) * readout; }

/** Holds the measured (uncompensated) keypoint positions and depths of one frame and writes
 * compensated ones into its FrameFeatures for given rates, as often as the rates change. */
class RollingShutterCompensator
{
   public:
	/** Remembers f's measured positions and depths; readout [s] >= 0 (0: nothing changes). */
	RollingShutterCompensator(const FrameFeatures& f, double readout);

	/** Writes into f (the frame given to the constructor, or a copy of it) the positions and
	 * depths compensated for `rates`, and rebuilds its area grid. Zero rates restore the
	 * measurements. */
	void apply(FrameFeatures& f, const CameraRates& rates, const PinholeIntrinsics& K) const;

   private:
	std::vector<cv::Point2f> m_measured;
	std::vector<float> m_depth;
	std::vector<float> m_rowTime;  // tau of each keypoint [s]
};

}  // namespace keygrid::sfm

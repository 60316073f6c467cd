#include <keygrid/core/FrameConventions.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/CVectorFixed.h>

namespace keygrid::core
{
const mrpt::poses::CPose3D& T_depth_cam()
{
	// Columns are the optical axes written in the depth frame: x_cam (right) = -Y,
	// y_cam (down) = -Z, z_cam (forward) = +X. Built from exact zeros and ones (not from
	// yaw/roll angles) so that conversions introduce no rounding.
	static const mrpt::poses::CPose3D T = [] {
		mrpt::math::CMatrixDouble33 R;
		R(0, 0) = 0, R(0, 1) = 0, R(0, 2) = 1;
		R(1, 0) = -1, R(1, 1) = 0, R(1, 2) = 0;
		R(2, 0) = 0, R(2, 1) = -1, R(2, 2) = 0;
		return mrpt::poses::CPose3D::FromRotationAndTranslation(
			R, mrpt::math::CVectorFixedDouble<3>::Zero());
	}();
	return T;
}

mrpt::math::TPoint3D camToMrptDepth(const mrpt::math::TPoint3D& p)
{
	return {p.z, -p.x, -p.y};
}

mrpt::math::TPoint3D mrptDepthToCam(const mrpt::math::TPoint3D& p)
{
	return {-p.y, -p.z, p.x};
}

mrpt::poses::CPose3D cameraPoseFromSensorPose(const mrpt::poses::CPose3D& T_world_depth)
{
	return T_world_depth + T_depth_cam();
}

mrpt::poses::CPose3D sensorPoseFromCameraPose(const mrpt::poses::CPose3D& T_world_cam)
{
	return T_world_cam + (-T_depth_cam());
}

}  // namespace keygrid::core

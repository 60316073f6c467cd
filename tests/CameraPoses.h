#pragma once
/** \file CameraPoses.h
 * Camera poses for synthetic test scenes, in the optical convention of keygrid's frames
 * (x right, y down, z forward).
 */
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/math/geometry.h>
#include <mrpt/poses/CPose3D.h>

#include <cmath>

namespace keygrid::test
{
/** The optical camera at `position` whose axes, in the parent frame, are `right`, `down` and
 * `forward` (orthonormal, right-handed). */
inline mrpt::poses::CPose3D opticalPose(
	const mrpt::math::TVector3D& right, const mrpt::math::TVector3D& down, const mrpt::math::TVector3D& forward,
	const mrpt::math::TPoint3D& position)
{
	mrpt::math::CMatrixDouble33 R;
	mrpt::math::CVectorFixedDouble<3> t;
	for (int i = 0; i < 3; i++)
	{
		R(i, 0) = right[i];
		R(i, 1) = down[i];
		R(i, 2) = forward[i];
		t[i] = position[i];
	}
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}

/** The optical camera at (x, y, h) of a z-up frame, heading `yaw` (about z, from +x) and pitched
 * down by `pitch` [rad]; its image rows stay horizontal. */
inline mrpt::poses::CPose3D levelOpticalPose(double x, double y, double h, double yaw, double pitch)
{
	const mrpt::math::TVector3D forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch));
	const mrpt::math::TVector3D right(std::sin(yaw), -std::cos(yaw), 0);
	return opticalPose(right, mrpt::math::crossProduct3D(forward, right), forward, mrpt::math::TPoint3D(x, y, h));
}
}  // namespace keygrid::test

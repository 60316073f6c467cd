#include <keygrid/sfm/Triangulation.h>

#include <Eigen/SVD>
#include <cmath>

namespace keygrid::sfm
{
namespace
{
Eigen::Matrix<double, 3, 4> projection(const mrpt::poses::CPose3D& T_world_cam, const PinholeIntrinsics& K)
{
	const mrpt::poses::CPose3D T = -T_world_cam;  // T_cam_world
	Eigen::Matrix<double, 3, 4> Rt;
	const auto R = T.getRotationMatrix();
	for (int i = 0; i < 3; i++)
	{
		for (int j = 0; j < 3; j++) Rt(i, j) = R(i, j);
		Rt(i, 3) = T.m_coords[i];
	}
	Eigen::Matrix3d Km;
	Km << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1;
	return Km * Rt;
}
}  // namespace

bool triangulateDlt(
	const mrpt::poses::CPose3D& T1, const Eigen::Vector2d& uv1, const mrpt::poses::CPose3D& T2,
	const Eigen::Vector2d& uv2, const PinholeIntrinsics& K, Eigen::Vector3d& p)
{
	const auto P1 = projection(T1, K), P2 = projection(T2, K);
	Eigen::Matrix4d A;
	A.row(0) = uv1.x() * P1.row(2) - P1.row(0);
	A.row(1) = uv1.y() * P1.row(2) - P1.row(1);
	A.row(2) = uv2.x() * P2.row(2) - P2.row(0);
	A.row(3) = uv2.y() * P2.row(2) - P2.row(1);
	Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
	const Eigen::Vector4d X = svd.matrixV().col(3);
	if (std::abs(X(3)) < 1e-12) return false;
	p = X.head<3>() / X(3);
	for (const auto* T : {&T1, &T2})
	{
		double x, y, z;
		(-*T).composePoint(p.x(), p.y(), p.z(), x, y, z);
		if (z <= 0) return false;
	}
	return true;
}

double parallaxAngle(const mrpt::poses::CPose3D& T1, const mrpt::poses::CPose3D& T2, const Eigen::Vector3d& p)
{
	const Eigen::Vector3d r1 = p - Eigen::Vector3d(T1.x(), T1.y(), T1.z());
	const Eigen::Vector3d r2 = p - Eigen::Vector3d(T2.x(), T2.y(), T2.z());
	const double c = r1.dot(r2) / std::max(1e-12, r1.norm() * r2.norm());
	return std::acos(std::clamp(c, -1.0, 1.0));
}

}  // namespace keygrid::sfm

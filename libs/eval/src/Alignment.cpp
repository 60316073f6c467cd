#include <keygrid/eval/Alignment.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <stdexcept>
#include <string>

namespace keygrid::eval
{
Similarity3 alignPointSets(
	const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y, bool withScale)
{
	if (x.size() != y.size())
		throw std::invalid_argument(
			"alignPointSets: " + std::to_string(x.size()) + " vs " + std::to_string(y.size()) +
			" points");
	if (x.size() < 3)
		throw std::invalid_argument(
			"alignPointSets: need at least 3 matched positions, got " + std::to_string(x.size()));
	const double n = static_cast<double>(x.size());
	Eigen::Vector3d mx = Eigen::Vector3d::Zero(), my = Eigen::Vector3d::Zero();
	for (std::size_t i = 0; i < x.size(); i++)
	{
		mx += x[i];
		my += y[i];
	}
	mx /= n;
	my /= n;
	Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
	double varX = 0;
	for (std::size_t i = 0; i < x.size(); i++)
	{
		const Eigen::Vector3d dx = x[i] - mx, dy = y[i] - my;
		S += dy * dx.transpose();
		varX += dx.squaredNorm();
	}
	S /= n;
	varX /= n;
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
	const Eigen::Vector3d D = svd.singularValues();
	// All points coincide: no rotation can be observed; keep the identity.
	// (Collinear points leave the roll about the line free; U W V^T is then one of the optima.)
	if (D(0) <= 1e-15 || varX <= 1e-30)
	{
		Similarity3 out;
		out.t = my - mx;
		return out;
	}
	Eigen::Vector3d w(1, 1, 1);
	if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) w(2) = -1;
	Similarity3 out;
	out.R = svd.matrixU() * w.asDiagonal() * svd.matrixV().transpose();
	out.s = withScale ? D.dot(w) / varX : 1.0;
	out.t = my - out.s * out.R * mx;
	return out;
}

Eigen::Matrix3d chordalMeanRotation(const std::vector<Eigen::Matrix3d>& Rx, const std::vector<Eigen::Matrix3d>& Ry)
{
	if (Rx.size() != Ry.size() || Rx.empty())
		throw std::invalid_argument("chordalMeanRotation: " + std::to_string(Rx.size()) + " vs " + std::to_string(Ry.size()) + " rotations");
	Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
	for (std::size_t k = 0; k < Rx.size(); k++) M += Ry[k] * Rx[k].transpose();
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
	Eigen::Matrix3d W = Eigen::Matrix3d::Identity();
	if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) W(2, 2) = -1;
	return svd.matrixU() * W * svd.matrixV().transpose();
}

Similarity3 alignPoses(const std::vector<mrpt::poses::CPose3D>& x, const std::vector<mrpt::poses::CPose3D>& y)
{
	if (x.size() != y.size() || x.empty())
		throw std::invalid_argument("alignPoses: " + std::to_string(x.size()) + " vs " + std::to_string(y.size()) + " poses");
	std::vector<Eigen::Matrix3d> Rx, Ry;
	for (std::size_t k = 0; k < x.size(); k++)
	{
		Rx.push_back(x[k].getRotationMatrix().asEigen());
		Ry.push_back(y[k].getRotationMatrix().asEigen());
	}
	Similarity3 out;
	out.R = chordalMeanRotation(Rx, Ry);
	Eigen::Vector3d t = Eigen::Vector3d::Zero();
	for (std::size_t k = 0; k < x.size(); k++)
		t += Eigen::Vector3d(y[k].x(), y[k].y(), y[k].z()) - out.R * Eigen::Vector3d(x[k].x(), x[k].y(), x[k].z());
	out.t = t / static_cast<double>(x.size());
	return out;
}

mrpt::poses::CPose3D rigidPose(const Similarity3& a)
{
	mrpt::math::CMatrixDouble44 H;
	H.setIdentity();
	for (int r = 0; r < 3; r++)
	{
		for (int c = 0; c < 3; c++) H(r, c) = a.R(r, c);
		H(r, 3) = a.t(r);
	}
	return mrpt::poses::CPose3D(H);
}

}  // namespace keygrid::eval

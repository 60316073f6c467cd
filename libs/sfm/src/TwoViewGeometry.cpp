#include <keygrid/sfm/TwoViewGeometry.h>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include <array>
#include <cmath>

namespace keygrid::sfm
{
namespace
{
/** Relative size of the second-smallest singular value of a DLT design matrix below which its
 * null space is not one-dimensional (degenerate sample). */
constexpr double kDegenerateDlt = 1e-9;

Eigen::Vector3d apply(const Eigen::Matrix3d& T, const Eigen::Vector2d& x)
{
	return T * Eigen::Vector3d(x.x(), x.y(), 1.0);
}

/** The right singular vector of A (rows x 9, zero-padded to >= 9 rows so that all nine
 * singular values exist) for its smallest singular value; false when the second-smallest is
 * also ~0 (the solution is not unique). */
bool nullVector(const Eigen::Matrix<double, Eigen::Dynamic, 9>& A, Eigen::Matrix<double, 9, 1>& h)
{
	Eigen::Matrix<double, Eigen::Dynamic, 9> M = A;
	if (M.rows() < 9)
	{
		M.conservativeResize(9, 9);
		M.bottomRows(9 - A.rows()).setZero();
	}
	Eigen::JacobiSVD<Eigen::Matrix<double, Eigen::Dynamic, 9>> svd(M, Eigen::ComputeFullV);
	const auto& s = svd.singularValues();
	if (!(s(0) > 0) || s(7) < kDegenerateDlt * s(0)) return false;
	h = svd.matrixV().col(8);
	return true;
}

Eigen::Matrix3d reshape(const Eigen::Matrix<double, 9, 1>& h)
{
	Eigen::Matrix3d M;
	M << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
	return M;
}
}  // namespace

Eigen::Matrix3d hartleyNormalisation(const std::vector<Eigen::Vector2d>& pts)
{
	Eigen::Matrix3d T = Eigen::Matrix3d::Identity();
	if (pts.size() < 2) return T;
	Eigen::Vector2d c = Eigen::Vector2d::Zero();
	for (const auto& p : pts) c += p;
	c /= static_cast<double>(pts.size());
	double meanDist = 0;
	for (const auto& p : pts) meanDist += (p - c).norm();
	meanDist /= static_cast<double>(pts.size());
	if (!(meanDist > 0)) return T;
	const double s = std::sqrt(2.0) / meanDist;
	T << s, 0, -s * c.x(), 0, s, -s * c.y(), 0, 0, 1;
	return T;
}

bool homographyDlt(
	const std::vector<Eigen::Vector2d>& x_ref, const std::vector<Eigen::Vector2d>& x_cur, Eigen::Matrix3d& H)
{
	const auto n = x_ref.size();
	if (n < 4 || x_cur.size() != n) return false;
	const Eigen::Matrix3d Tr = hartleyNormalisation(x_ref), Tc = hartleyNormalisation(x_cur);
	// x_cur x (H x_ref) = 0 with x_cur = (u, v, 1): rows for the 1st and 2nd components,
	//   [ 0^T, -x_ref^T, v x_ref^T ] h = 0,   [ x_ref^T, 0^T, -u x_ref^T ] h = 0.
	Eigen::Matrix<double, Eigen::Dynamic, 9> A(2 * n, 9);
	for (std::size_t i = 0; i < n; i++)
	{
		const Eigen::Vector3d a = apply(Tr, x_ref[i]), b = apply(Tc, x_cur[i]);
		A.row(2 * i) << 0, 0, 0, -a.transpose(), b.y() * a.transpose();
		A.row(2 * i + 1) << a.transpose(), 0, 0, 0, -b.x() * a.transpose();
	}
	Eigen::Matrix<double, 9, 1> h;
	if (!nullVector(A, h)) return false;
	H = Tc.inverse() * reshape(h) * Tr;  // x_cur = Tc^-1 Hn Tr x_ref
	H /= H.norm();
	return H.allFinite();
}

bool fundamentalEightPoint(
	const std::vector<Eigen::Vector2d>& x_ref, const std::vector<Eigen::Vector2d>& x_cur, Eigen::Matrix3d& F)
{
	const auto n = x_ref.size();
	if (n < 8 || x_cur.size() != n) return false;
	const Eigen::Matrix3d Tr = hartleyNormalisation(x_ref), Tc = hartleyNormalisation(x_cur);
	// x_cur^T F x_ref = sum_jk b_j a_k F_jk: the row is (b_j a_k) in row-major order of F.
	Eigen::Matrix<double, Eigen::Dynamic, 9> A(n, 9);
	for (std::size_t i = 0; i < n; i++)
	{
		const Eigen::Vector3d a = apply(Tr, x_ref[i]), b = apply(Tc, x_cur[i]);
		A.row(i) << b.x() * a.transpose(), b.y() * a.transpose(), a.transpose();
	}
	Eigen::Matrix<double, 9, 1> f;
	if (!nullVector(A, f)) return false;
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(reshape(f), Eigen::ComputeFullU | Eigen::ComputeFullV);
	Eigen::Vector3d s = svd.singularValues();
	s(2) = 0;  // closest rank-2 matrix in the Frobenius norm (Eckart-Young)
	const Eigen::Matrix3d Fn = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
	F = Tc.transpose() * Fn * Tr;  // (Tc b)^T Fn (Tr a) = b^T (Tc^T Fn Tr) a
	F /= F.norm();
	return F.allFinite();
}

std::vector<RelativeMotion> decomposeEssential(const Eigen::Matrix3d& E)
{
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
	Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
	// E and -E are the same model: flip the null columns so that U and V are rotations, and
	// then U W V^T is one too.
	if (U.determinant() < 0) U.col(2) *= -1;
	if (V.determinant() < 0) V.col(2) *= -1;
	Eigen::Matrix3d W;
	W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
	const Eigen::Vector3d t = U.col(2).normalized();
	const Eigen::Matrix3d R1 = U * W * V.transpose(), R2 = U * W.transpose() * V.transpose();
	return {{R1, t}, {R1, -t}, {R2, t}, {R2, -t}};
}

/* Faugeras & Lustman (1988). A plane n^T X_ref = d maps the reference to the current camera by
 * X_cur = R X_ref + t = (R + t n^T / d) X_ref, so A = K^-1 H K = lambda (R + t n^T / d). With
 * the SVD A = U diag(d1, d2, d3) V^T (d1 >= d2 >= d3) and s = det(U) det(V), write
 *   diag(d1, d2, d3) = d' R' + t' n'^T,  R = s U R' V^T,  t = U t',  n = V n',  d = s d'.
 * R' keeps the axis e2 orthogonal to n' (both n' and the rotation axis lie in the e1-e3
 * plane), which forces d' = +-d2. With n' = (x1, 0, x3), x1 = e1 sqrt((d1^2-d2^2)/(d1^2-d3^2)),
 * x3 = e3 sqrt((d2^2-d3^2)/(d1^2-d3^2)) (four sign choices e1, e3):
 *  d' = +d2: R' = [c 0 -s; 0 1 0; s 0 c],  c = (d2^2 + d1 d3) / ((d1 + d3) d2),
 *            s = (d1 - d3) x1 x3 / d2,      t' = (d1 - d3) (x1, 0, -x3);
 *  d' = -d2: R' = [c 0 s; 0 -1 0; s 0 -c],  c = (d1 d3 - d2^2) / ((d1 - d3) d2),
 *            s = (d1 + d3) x1 x3 / d2,      t' = (d1 + d3) (x1, 0, x3).
 * (Multiplying out d' R' + t' n'^T gives diag(d1, d2, d3) entry by entry.) Each R comes with
 * both signs of t (e1, e3 -> -e1, -e3), so the unknown sign of lambda only permutes the set.
 * Cheirality keeps one of the eight. */
std::vector<RelativeMotion> decomposeHomography(const Eigen::Matrix3d& A, double minGap)
{
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
	const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
	const double s = U.determinant() * V.determinant();
	const double d1 = svd.singularValues()(0), d2 = svd.singularValues()(1), d3 = svd.singularValues()(2);
	if (!(d3 > 0) || d1 / d2 < 1.0 + minGap || d2 / d3 < 1.0 + minGap) return {};
	const double a1 = std::sqrt((d1 * d1 - d2 * d2) / (d1 * d1 - d3 * d3));
	const double a3 = std::sqrt((d2 * d2 - d3 * d3) / (d1 * d1 - d3 * d3));
	const std::array<double, 4> e1{1, 1, -1, -1}, e3{1, -1, 1, -1};
	std::vector<RelativeMotion> out;
	out.reserve(8);
	for (int sign : {+1, -1})  // d' = sign * d2
	{
		for (int k = 0; k < 4; k++)
		{
			const double x1 = e1[k] * a1, x3 = e3[k] * a3;
			Eigen::Matrix3d Rp;
			Eigen::Vector3d tp;
			if (sign > 0)
			{
				const double c = (d2 * d2 + d1 * d3) / ((d1 + d3) * d2), sn = (d1 - d3) * x1 * x3 / d2;
				Rp << c, 0, -sn, 0, 1, 0, sn, 0, c;
				tp << (d1 - d3) * x1, 0, -(d1 - d3) * x3;
			}
			else
			{
				const double c = (d1 * d3 - d2 * d2) / ((d1 - d3) * d2), sn = (d1 + d3) * x1 * x3 / d2;
				Rp << c, 0, sn, 0, -1, 0, sn, 0, -c;
				tp << (d1 + d3) * x1, 0, (d1 + d3) * x3;
			}
			out.push_back({s * U * Rp * V.transpose(), (U * tp).normalized()});
		}
	}
	return out;
}

bool triangulateRays(
	const Eigen::Vector3d& ray_ref, const Eigen::Vector3d& ray_cur, const RelativeMotion& m, Eigen::Vector3d& X_ref)
{
	Eigen::Matrix<double, 3, 4> P;
	P << m.R_cur_ref, m.t_cur_ref;
	Eigen::Matrix4d A;
	// Reference view P = [I | 0]: rows x e3^T - e1^T and y e3^T - e2^T.
	A.row(0) << -1, 0, ray_ref.x(), 0;
	A.row(1) << 0, -1, ray_ref.y(), 0;
	A.row(2) = ray_cur.x() * P.row(2) - P.row(0);
	A.row(3) = ray_cur.y() * P.row(2) - P.row(1);
	Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
	const Eigen::Vector4d X = svd.matrixV().col(3);
	if (std::abs(X(3)) < 1e-12 * X.head<3>().norm()) return false;
	X_ref = X.head<3>() / X(3);
	return X_ref.allFinite();
}

}  // namespace keygrid::sfm

/** \file BundleSystem.cpp
 * Index, linearisation and reduced camera system of the dedicated bundle solver
 * (detail/BundleSystem.h; the equations are in BundleLevenbergMarquardt.h).
 */
#include "detail/BundleSystem.h"

#include "detail/RobustReprojection.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace keygrid::sfm::detail
{
BundleIndex::BundleIndex(const std::vector<BundleCamera>& cameras, std::size_t points, const std::vector<BundleTerm>& terms)
{
	var.assign(cameras.size(), -1);
	for (std::size_t i = 0; i < cameras.size(); i++)
		if (!cameras[i].fixed) var[i] = moving++;
	pointBegin.assign(points + 1, 0);
	for (std::size_t k = 0; k < terms.size(); k++)
	{
		const auto& t = terms[k];
		if (t.camera < 0 || static_cast<std::size_t>(t.camera) >= cameras.size() || t.point < 0 ||
			static_cast<std::size_t>(t.point) >= points)
			throw std::invalid_argument(
				"solveBundleLevenbergMarquardt: term " + std::to_string(k) + " refers to camera " + std::to_string(t.camera) +
				" / point " + std::to_string(t.point) + " (have " + std::to_string(cameras.size()) + " / " +
				std::to_string(points) + ")");
		if (k > 0 && t.point < terms[k - 1].point)
			throw std::invalid_argument("solveBundleLevenbergMarquardt: terms must be sorted by point (term " + std::to_string(k) + ")");
		pointBegin[static_cast<std::size_t>(t.point) + 1]++;
	}
	for (std::size_t j = 0; j < points; j++) pointBegin[j + 1] += pointBegin[j];
	// Split the points where half of the terms are done.
	partBegin[0] = 0;
	partBegin[kBundlePartitions] = points;
	for (int part = 1; part < kBundlePartitions; part++)
	{
		const std::size_t target = terms.size() * static_cast<std::size_t>(part) / kBundlePartitions;
		partBegin[part] = static_cast<std::size_t>(std::upper_bound(pointBegin.begin(), pointBegin.end() - 1, target) - pointBegin.begin());
		partBegin[part] = std::clamp(partBegin[part], partBegin[part - 1], points);
	}
}

bool BundleLinearization::evaluate(
	const BundleIndex& index, const std::vector<BundleCamera>& cameras, const std::vector<Eigen::Vector3d>& points,
	const std::vector<BundleTerm>& terms, const PinholeIntrinsics& K, double bf)
{
	const auto n = static_cast<std::size_t>(index.moving);
	V.resize(points.size());
	gp.resize(points.size());
	W.resize(terms.size());
	struct Part
	{
		double cost{0};
		std::vector<Matrix6d> U;
		Eigen::VectorXd gc;
		bool ok{true};
	};
	Part parts[kBundlePartitions];
	forEachPartition(
		[&](int p)
		{
			Part& s = parts[p];
			s.U.assign(n, Matrix6d::Zero());
			s.gc = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(n));
			for (std::size_t j = index.partBegin[p]; j < index.partBegin[p + 1] && s.ok; j++)
			{
				V[j].setZero();
				gp[j].setZero();
				for (std::size_t k = index.pointBegin[j]; k < index.pointBegin[j + 1]; k++)
				{
					const auto& term = terms[k];
					const auto& cam = cameras[static_cast<std::size_t>(term.camera)];
					const Eigen::Vector3d Rp = cam.R_cam_world * points[j];
					const Eigen::Vector3d pc = Rp + cam.t_cam_world;
					Eigen::Vector3d r;
					if (!residualAt(pc, term, K, bf, r))
					{
						s.ok = false;
						break;
					}
					double rho, rho1;
					huber(r.squaredNorm(), term.huberDelta, rho, rho1);
					s.cost += 0.5 * rho;
					const Eigen::Matrix3d Jpc = residualJacobian(pc, term, K, bf);
					const Eigen::Matrix3d Jp = Jpc * cam.R_cam_world;
					V[j].noalias() += rho1 * (Jp.transpose() * Jp);
					gp[j].noalias() += rho1 * (Jp.transpose() * r);
					const int v = index.var[static_cast<std::size_t>(term.camera)];
					if (v < 0)
					{
						W[k].setZero();
						continue;
					}
					Eigen::Matrix<double, 3, 6> Jc;
					Jc.leftCols<3>() = -Jpc * skew(Rp);
					Jc.rightCols<3>() = Jpc;
					s.U[static_cast<std::size_t>(v)].noalias() += rho1 * (Jc.transpose() * Jc);
					s.gc.segment<6>(6 * v).noalias() += rho1 * (Jc.transpose() * r);
					W[k].noalias() = rho1 * (Jc.transpose() * Jp);
				}
			}
		});
	cost = 0;
	U.assign(n, Matrix6d::Zero());
	gc = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(n));
	for (const auto& s : parts)
	{
		if (!s.ok) return false;
		cost += s.cost;
		for (std::size_t i = 0; i < n; i++) U[i] += s.U[i];
		gc += s.gc;
	}
	return true;
}

double BundleLinearization::gradientMaxNorm() const
{
	double m = gc.size() > 0 ? gc.lpNorm<Eigen::Infinity>() : 0.0;
	for (const auto& g : gp) m = std::max(m, g.lpNorm<Eigen::Infinity>());
	return m;
}

double BundleLinearization::modelChange(
	const BundleIndex& index, const std::vector<BundleTerm>& terms, const Eigen::VectorXd& dc,
	const std::vector<Eigen::Vector3d>& dp) const
{
	// step^T H step = sum_i dc_i^T U_i dc_i + sum_j dp_j^T V_j dp_j + 2 sum_ij dc_i^T W_ij dp_j
	double cameras = 0;
	for (int i = 0; i < index.moving; i++)
	{
		const Vector6d d = dc.segment<6>(6 * i);
		cameras += gc.segment<6>(6 * i).dot(d) + 0.5 * d.dot(U[static_cast<std::size_t>(i)] * d);
	}
	double parts[kBundlePartitions] = {0, 0};
	forEachPartition(
		[&](int p)
		{
			double sum = 0;
			for (std::size_t j = index.partBegin[p]; j < index.partBegin[p + 1]; j++)
			{
				sum += gp[j].dot(dp[j]) + 0.5 * dp[j].dot(V[j] * dp[j]);
				for (std::size_t k = index.pointBegin[j]; k < index.pointBegin[j + 1]; k++)
				{
					const int v = index.var[static_cast<std::size_t>(terms[k].camera)];
					if (v >= 0) sum += dc.segment<6>(6 * v).dot(W[k] * dp[j]);
				}
			}
			parts[p] = sum;
		});
	return cameras + parts[0] + parts[1];
}

ReducedCameraSystem::ReducedCameraSystem(const BundleIndex& index, const std::vector<BundleTerm>& terms)
	: m_index(index), m_terms(terms)
{
	// Blocks: every camera's diagonal, and each pair of moving cameras sharing a point.
	std::vector<std::pair<int, int>> pairs;
	for (int i = 0; i < index.moving; i++) pairs.emplace_back(i, i);
	const auto movingTerms = [&](std::size_t j)
	{
		std::vector<int> vars;
		for (std::size_t k = index.pointBegin[j]; k < index.pointBegin[j + 1]; k++)
			if (const int v = index.var[static_cast<std::size_t>(terms[k].camera)]; v >= 0) vars.push_back(v);
		return vars;
	};
	for (std::size_t j = 0; j < index.points(); j++)
	{
		const auto vars = movingTerms(j);
		for (std::size_t a = 0; a < vars.size(); a++)
			for (std::size_t b = 0; b < a; b++) pairs.emplace_back(std::max(vars[a], vars[b]), std::min(vars[a], vars[b]));
	}
	std::sort(pairs.begin(), pairs.end());
	pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
	m_blocks = std::move(pairs);
	const auto blockOf = [&](int a, int b)
	{ return static_cast<int>(std::lower_bound(m_blocks.begin(), m_blocks.end(), std::make_pair(std::max(a, b), std::min(a, b))) - m_blocks.begin()); };
	m_pairBegin.assign(index.points() + 1, 0);
	for (std::size_t j = 0; j < index.points(); j++)
	{
		const auto vars = movingTerms(j);
		for (std::size_t a = 0; a < vars.size(); a++)
			for (std::size_t b = 0; b <= a; b++) m_pairBlock.push_back(blockOf(vars[a], vars[b]));
		m_pairBegin[j + 1] = m_pairBlock.size();
	}
	// The scalar pattern (lower triangle), then where each block entry lives in it.
	const Eigen::Index dim = 6 * static_cast<Eigen::Index>(index.moving);
	std::vector<Eigen::Triplet<double>> pattern;
	pattern.reserve(m_blocks.size() * 36);
	for (const auto& [r, c] : m_blocks)
		for (int rr = 0; rr < 6; rr++)
			for (int cc = 0; cc < 6; cc++)
				if (r != c || rr >= cc) pattern.emplace_back(6 * r + rr, 6 * c + cc, 1.0);
	m_S.resize(dim, dim);
	m_S.setFromTriplets(pattern.begin(), pattern.end());
	m_S.makeCompressed();
	m_valueIndex.assign(m_blocks.size() * 36, -1);
	for (std::size_t k = 0; k < m_blocks.size(); k++)
	{
		const auto [r, c] = m_blocks[k];
		for (int cc = 0; cc < 6; cc++)
		{
			const int col = 6 * c + cc;
			const int* begin = m_S.innerIndexPtr() + m_S.outerIndexPtr()[col];
			const int* end = m_S.innerIndexPtr() + m_S.outerIndexPtr()[col + 1];
			for (int rr = (r == c ? cc : 0); rr < 6; rr++)
				m_valueIndex[36 * k + 6 * rr + cc] = static_cast<int>(std::lower_bound(begin, end, 6 * r + rr) - m_S.innerIndexPtr());
		}
	}
	if (dim > 0) m_cholesky.analyzePattern(m_S);
	m_Vinv.resize(index.points());
}

void ReducedCameraSystem::eliminatePoints(const BundleLinearization& lin, int part, PartSums& sums)
{
	sums.blocks.assign(m_blocks.size(), Matrix6d::Zero());
	sums.rhs = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(m_index.moving));
	std::vector<Matrix63> Y;  // W_a (V + D)^-1 of the point's moving terms
	std::vector<int> vars;
	std::vector<std::size_t> ks;
	for (std::size_t j = m_index.partBegin[part]; j < m_index.partBegin[part + 1]; j++)
	{
		Eigen::Matrix3d Vd = lin.V[j];
		for (int k = 0; k < 3; k++) Vd(k, k) += m_pointDamping[3 * j + k];
		m_Vinv[j] = Vd.inverse();  // each part writes its own points
		Y.clear();
		vars.clear();
		ks.clear();
		for (std::size_t k = m_index.pointBegin[j]; k < m_index.pointBegin[j + 1]; k++)
		{
			const int v = m_index.var[static_cast<std::size_t>(m_terms[k].camera)];
			if (v < 0) continue;
			Y.push_back(lin.W[k] * m_Vinv[j]);
			vars.push_back(v);
			ks.push_back(k);
			sums.rhs.segment<6>(6 * v).noalias() += Y.back() * lin.gp[j];
		}
		std::size_t pair = m_pairBegin[j];
		for (std::size_t a = 0; a < Y.size(); a++)
			for (std::size_t b = 0; b <= a; b++)
			{
				Matrix6d& block = sums.blocks[static_cast<std::size_t>(m_pairBlock[pair++])];
				// Block (row, column) with row >= column gets -W_row V^-1 W_column^T.
				if (vars[a] > vars[b] || a == b)
					block.noalias() -= Y[a] * lin.W[ks[b]].transpose();
				else if (vars[a] < vars[b])
					block.noalias() -= Y[b] * lin.W[ks[a]].transpose();
				else  // one camera observing the point twice
					block.noalias() -= Y[a] * lin.W[ks[b]].transpose() + Y[b] * lin.W[ks[a]].transpose();
			}
	}
}

bool ReducedCameraSystem::factorAndSolve(
	const BundleLinearization& lin, const std::vector<double>& cameraDamping, Eigen::VectorXd& dc)
{
	const int n = m_index.moving;
	dc = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(n));
	if (n == 0) return true;
	double* values = m_S.valuePtr();
	for (std::size_t k = 0; k < m_blocks.size(); k++)
	{
		Matrix6d block = m_parts[0].blocks[k] + m_parts[1].blocks[k];
		const auto [r, c] = m_blocks[k];
		if (r == c)
		{
			block += lin.U[static_cast<std::size_t>(r)];
			for (int d = 0; d < 6; d++) block(d, d) += cameraDamping[6 * static_cast<std::size_t>(r) + d];
		}
		for (int e = 0; e < 36; e++)
			if (const int at = m_valueIndex[36 * k + e]; at >= 0) values[at] = block(e / 6, e % 6);
	}
	const Eigen::VectorXd rhs = -lin.gc + m_parts[0].rhs + m_parts[1].rhs;
	m_cholesky.factorize(m_S);
	if (m_cholesky.info() != Eigen::Success) return false;
	dc = m_cholesky.solve(rhs);
	return m_cholesky.info() == Eigen::Success && dc.allFinite();
}

void ReducedCameraSystem::backSubstitute(
	const BundleLinearization& lin, const Eigen::VectorXd& dc, std::vector<Eigen::Vector3d>& dp) const
{
	dp.resize(m_index.points());
	forEachPartition(
		[&](int part)
		{
			for (std::size_t j = m_index.partBegin[part]; j < m_index.partBegin[part + 1]; j++)
			{
				Eigen::Vector3d b = -lin.gp[j];
				for (std::size_t k = m_index.pointBegin[j]; k < m_index.pointBegin[j + 1]; k++)
					if (const int v = m_index.var[static_cast<std::size_t>(m_terms[k].camera)]; v >= 0)
						b.noalias() -= lin.W[k].transpose() * dc.segment<6>(6 * v);
				dp[j] = m_Vinv[j] * b;
			}
		});
}

}  // namespace keygrid::sfm::detail

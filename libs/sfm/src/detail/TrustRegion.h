#pragma once
/** \file TrustRegion.h
 * The Levenberg-Marquardt trust region of the dedicated solvers (pose, bundle), with Ceres'
 * defaults: damping D / radius with D = diag(J^T W J) clamped to [1e-6, 1e32]; a step is
 * accepted when the actual cost decrease is more than 1e-3 of the model's; the radius grows
 * by 1 / max(1/3, 1 - (2 rho - 1)^3) after an accepted step and halves (then quarters, ...)
 * after a rejected one.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace keygrid::sfm::detail
{
class TrustRegion
{
   public:
	static constexpr double kMinRelativeDecrease = 1e-3;

	explicit TrustRegion(double initialRadius) : m_radius(initialRadius) {}

	/** The damping added to a diagonal entry `diag` of J^T W J. */
	double damping(double diag) const { return std::clamp(diag, kMinDiagonal, kMaxDiagonal) / m_radius; }
	/** Whether a step with this actual and model cost decrease is taken. */
	static bool accepts(double actualDecrease, double modelDecrease)
	{
		return modelDecrease > 0 && actualDecrease / modelDecrease > kMinRelativeDecrease;
	}
	/** After an accepted step of gain ratio rho = actual / model decrease. */
	void grow(double rho)
	{
		m_radius = std::min(kMaxRadius, m_radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
		m_decreaseFactor = 2.0;
	}
	/** After a rejected step; false once the radius is below its floor (give up). */
	bool shrink()
	{
		m_radius /= m_decreaseFactor;
		m_decreaseFactor *= 2.0;
		return m_radius >= kMinRadius;
	}

   private:
	static constexpr double kMinDiagonal = 1e-6, kMaxDiagonal = 1e32;
	static constexpr double kMaxRadius = 1e16, kMinRadius = 1e-32;
	double m_radius;
	double m_decreaseFactor{2.0};
};

/** Exp(w) of so(3): the rotation by |w| about w / |w| (first order below 1e-12 rad). */
inline Eigen::Matrix3d expSO3(const Eigen::Vector3d& w)
{
	const double angle = w.norm();
	if (angle < 1e-12)
	{
		Eigen::Matrix3d S;
		S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
		return Eigen::Matrix3d::Identity() + S;
	}
	return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

}  // namespace keygrid::sfm::detail

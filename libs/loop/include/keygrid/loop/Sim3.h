#pragma once
/** \file Sim3.h
 * Similarity transforms Sim(3): x -> s R x + t (rotation R as a unit quaternion, translation t,
 * scale s > 0). The vertex and edge type of the monocular pose graph (Sim3PoseGraph.h);
 * templated on the scalar so that its Ceres residual (RelativeSim3Error.h) composes with the
 * same code, with Scalar = ceres::Jet.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keygrid::loop
{
/** Named like poses: S_a_b maps b's coordinates into a's, so S_a_c = S_a_b * S_b_c and
 * (A * B) x = A (B x). With S_world_kf = (s, R, t), t is the camera centre and R the camera
 * orientation, as in the rigid pose (R, t); s converts the keyframe's camera coordinates (in
 * the map units of the time it was created) to world units. */
template <typename Scalar>
struct Sim3T
{
	using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
	using Quaternion = Eigen::Quaternion<Scalar>;
	using Isometry = Eigen::Transform<Scalar, 3, Eigen::Isometry>;

	Quaternion q{Quaternion::Identity()};  //!< rotation R, unit norm
	Vector3 t{Vector3::Zero()};
	Scalar s{1};

	/** The rigid transform with scale s. */
	static Sim3T fromIsometry(const Isometry& T, Scalar scale = Scalar(1))
	{
		return Sim3T{Quaternion(T.linear()).normalized(), T.translation(), scale};
	}

	/** Rotation and translation; the scale dropped. */
	Isometry rigid() const
	{
		Isometry T = Isometry::Identity();
		T.linear() = q.toRotationMatrix();
		T.translation() = t;
		return T;
	}

	/** (s_A, R_A, t_A) (s_B, R_B, t_B) = (s_A s_B, R_A R_B, s_A R_A t_B + t_A) */
	Sim3T operator*(const Sim3T& b) const { return Sim3T{q * b.q, s * (q * b.t) + t, s * b.s}; }

	Vector3 operator*(const Vector3& x) const { return s * (q * x) + t; }

	/** (s, R, t)^-1 = (1 / s, R^T, -R^T t / s) */
	Sim3T inverse() const
	{
		const Quaternion qInv = q.conjugate();
		return Sim3T{qInv, -(qInv * t) / s, Scalar(1) / s};
	}

	template <typename Other>
	Sim3T<Other> cast() const
	{
		return Sim3T<Other>{q.template cast<Other>(), t.template cast<Other>(), Other(s)};
	}
};

using Sim3 = Sim3T<double>;

}  // namespace keygrid::loop

// A consumer of an installed keygrid: uses its headers and libraries and checks one closed form.
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/eval/TrajectoryErrors.h>

#include <cmath>
#include <cstdio>

int main()
{
	using mrpt::poses::CPose3D;
	keygrid::core::Trajectory gt, est;
	// Square of side 1 m; the estimate scales the square by 1 + e about its centre, which
	// no rigid alignment can undo: every corner is off by e * sqrt(2)/2 from the centre.
	const double e = 0.1 * std::sqrt(2.0);
	const double xs[4] = {0.5, -0.5, -0.5, 0.5}, ys[4] = {0.5, 0.5, -0.5, -0.5};
	for (int i = 0; i < 4; i++)
	{
		gt.push_back({double(i), CPose3D(xs[i], ys[i], 0, 0, 0, 0)});
		est.push_back({double(i), CPose3D((1 + e) * xs[i], (1 + e) * ys[i], 0, 0, 0, 0)});
	}
	const auto r = keygrid::eval::evaluateTrajectory(gt, est);
	const auto cam = keygrid::core::RgbdCamera::Preset("fr1");
	std::printf("ATE %.6f m (fr1 fx %.3f)\n", r.ate.rmse, cam.fx);
	return std::abs(r.ate.rmse - 0.1) < 1e-9 ? 0 : 1;
}

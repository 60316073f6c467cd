/** \file floor_estimate_eval.cpp
 * keygrid_floor_estimate_eval: error of keygrid-slam's floor frame against a z-up ground
 * truth whose floor is z = 0 (keygrid-sim's world).
 *
 *   keygrid_floor_estimate_eval --gt GT.txt --traj trajectory.txt --report report.json [--name N]
 *       [--history]   (also one line per estimate)
 *
 * Each floor estimate T_world_floor of report.json ("floor": its "history" of accepted
 * estimates with the keyframe count and timestamp they were made at, and the final
 * "T_world_floor") is carried into the ground-truth world, T_gt_floor = T_gt_world *
 * T_world_floor, and scored by its tilt (angle between its z axis and +z) and height offset
 * (z of the estimated floor plane under the centroid of the ground-truth camera positions
 * up to the estimate's time). T_gt_world:
 *  - for the final estimate, the SE(3) Umeyama alignment of trajectory.txt (the final poses)
 *    to the ground truth at common timestamps;
 *  - for the estimates made during the run before its first loop closure, the world they
 *    were made in: the SLAM world is the first camera's frame, so T_gt_world = T_gt_cam(t0) *
 *    inverse(T_world_cam(t0)) with the first frame's online pose (trajectory_online.txt, next
 *    to trajectory.txt). A Umeyama alignment of the poses up to the estimate would leave the
 *    rotation about a short, nearly straight path unresolved;
 *  - for those made from the first loop closure on (report.json "loop_closures", its
 *    keyframe_timestamp), under corrected poses: the final alignment, as for the final one.
 * */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose3DQuat.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace keygrid;

namespace
{
const mrpt::poses::CPose3D* poseAt(const core::Trajectory& t, double stamp)
{
	auto it = std::lower_bound(t.begin(), t.end(), stamp, [](const core::StampedPose& p, double s) { return p.t < s; });
	for (auto c : {it, it == t.begin() ? it : it - 1})
		if (c != t.end() && std::abs(c->t - stamp) < 1e-4) return &c->T_world_cam;
	return nullptr;
}

mrpt::poses::CPose3D umeyama(const core::Trajectory& gt, const core::Trajectory& est, Eigen::Vector3d& gtCentroid)
{
	std::vector<Eigen::Vector3d> x, y;
	for (const auto& e : est)
		if (const auto* g = poseAt(gt, e.t))
		{
			x.emplace_back(e.T_world_cam.x(), e.T_world_cam.y(), e.T_world_cam.z());
			y.emplace_back(g->x(), g->y(), g->z());
		}
	if (x.size() < 3) throw std::runtime_error("fewer than 3 common timestamps between the trajectories");
	gtCentroid.setZero();
	for (const auto& p : y) gtCentroid += p;
	gtCentroid /= static_cast<double>(y.size());
	return eval::rigidPose(eval::alignPointSets(x, y, false));
}

struct Estimate
{
	long keyframes{-1};  //!< -1: the final one
	double stamp{0};
	mrpt::poses::CPose3D T_world_floor;
};

/** [x, y, z, qx, qy, qz, qw] as a pose. */
mrpt::poses::CPose3D poseFromJson(const nlohmann::json& a)
{
	if (!a.is_array() || a.size() != 7) throw std::runtime_error("bad pose " + a.dump());
	const auto v = a.get<std::vector<double>>();
	return mrpt::poses::CPose3D(mrpt::poses::CPose3DQuat(v[0], v[1], v[2], mrpt::math::CQuaternionDouble(v[6], v[3], v[4], v[5])));
}

nlohmann::json readReport(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw std::runtime_error("cannot read " + path);
	return nlohmann::json::parse(f);
}

/** The history and the final estimate of report.json's "floor" object. */
std::vector<Estimate> readEstimates(const nlohmann::json& report, const std::string& path)
{
	if (!report.contains("floor") || !report["floor"].is_object()) throw std::runtime_error(path + " has no floor frame");
	const auto& fl = report["floor"];
	std::vector<Estimate> out;
	for (const auto& h : fl.value("history", nlohmann::json::array()))
		out.push_back({h.at("keyframes").get<long>(), h.at("stamp").get<double>(), poseFromJson(h.at("T_world_floor"))});
	if (!fl.contains("T_world_floor") || fl["T_world_floor"].is_null()) throw std::runtime_error(path + ": the run has no floor frame");
	out.push_back({-1, 0.0, poseFromJson(fl["T_world_floor"])});
	return out;
}

struct Error
{
	double offset{0}, tiltDeg{0};
};

Error floorError(const mrpt::poses::CPose3D& T_gt_floor, const Eigen::Vector3d& c)
{
	const auto R = T_gt_floor.getRotationMatrix();
	const Eigen::Vector3d n(R(0, 2), R(1, 2), R(2, 2));
	const Eigen::Vector3d o(T_gt_floor.x(), T_gt_floor.y(), T_gt_floor.z());
	Error e;
	e.tiltDeg = std::acos(std::clamp(n.z(), -1.0, 1.0)) * 180.0 / M_PI;
	// Plane n.(p - o) = 0 at (c.x, c.y): z = o.z - (n.x (c.x - o.x) + n.y (c.y - o.y)) / n.z
	e.offset = o.z() - (n.x() * (c.x() - o.x()) + n.y() * (c.y() - o.y())) / n.z();
	return e;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		std::string gtPath, trajPath, reportPath, name = "-";
		bool history = false;
		for (int i = 1; i < argc; i++)
		{
			const std::string k = argv[i];
			if (k == "--history")
			{
				history = true;
				continue;
			}
			if (i + 1 >= argc) throw std::invalid_argument("missing value after " + k);
			const std::string v = argv[++i];
			if (k == "--gt") gtPath = v;
			else if (k == "--traj") trajPath = v;
			else if (k == "--report") reportPath = v;
			else if (k == "--name") name = v;
			else throw std::invalid_argument("unknown option " + k);
		}
		if (gtPath.empty() || trajPath.empty() || reportPath.empty())
			throw std::invalid_argument("usage: keygrid_floor_estimate_eval --gt GT.txt --traj trajectory.txt --report report.json [--name N]");
		const auto gt = core::readTumTrajectory(gtPath);
		const auto est = core::readTumTrajectory(trajPath);
		const std::string onlinePath = trajPath.substr(0, trajPath.find_last_of('/') + 1) + "trajectory_online.txt";
		const auto online = core::readTumTrajectory(onlinePath);
		Eigen::Vector3d centroidAll;
		const mrpt::poses::CPose3D T_gt_worldFinal = umeyama(gt, est, centroidAll);
		const auto* gt0 = online.empty() ? nullptr : poseAt(gt, online.front().t);
		if (!gt0) throw std::runtime_error(onlinePath + ": its first frame has no ground truth");
		const mrpt::poses::CPose3D T_gt_worldRun = *gt0 + (-online.front().T_world_cam);
		// Centroid of the ground-truth camera positions up to `stamp`.
		auto centroidUpTo = [&](double stamp) {
			Eigen::Vector3d c = Eigen::Vector3d::Zero();
			std::size_t n = 0;
			for (const auto& p : gt)
				if (p.t <= stamp + 1e-6)
				{
					c += Eigen::Vector3d(p.T_world_cam.x(), p.T_world_cam.y(), p.T_world_cam.z());
					n++;
				}
			return n ? Eigen::Vector3d(c / static_cast<double>(n)) : centroidAll;
		};
		const auto report = readReport(reportPath);
		const auto estimates = readEstimates(report, reportPath);
		double firstLoop = 1e300;
		if (const auto& loops = report.value("loop_closures", nlohmann::json::array()); !loops.empty())
			firstLoop = loops[0].at("keyframe_timestamp").get<double>();
		// The estimate in force at 10 keyframes: the last one from at most 10 (an unchanged
		// estimate is not repeated), else the first one after.
		const Estimate* at10 = nullptr;
		Error last;
		for (const auto& e : estimates)
			if (e.keyframes < 0)
				last = floorError(T_gt_worldFinal + e.T_world_floor, centroidAll);
			else if (e.keyframes <= 10 || !at10)
				at10 = &e;
		if (!at10) throw std::runtime_error(reportPath + ": no floor estimate in the history");
		auto runError = [&](const Estimate& e) {
			return floorError((e.stamp + 1e-6 >= firstLoop ? T_gt_worldFinal : T_gt_worldRun) + e.T_world_floor, centroidUpTo(e.stamp));
		};
		if (history)
			for (const auto& e : estimates)
				if (e.keyframes >= 0)
				{
					const Error err = runError(e);
					std::printf("estimate keyframes %ld stamp %.3f offset_cm %.2f tilt_deg %.2f\n", e.keyframes, e.stamp, 100 * err.offset, err.tiltDeg);
				}
		const Error e10 = runError(*at10);
		Error worst{std::abs(e10.offset), e10.tiltDeg};
		for (const auto& e : estimates)
			if (e.keyframes > at10->keyframes)
			{
				const Error err = runError(e);
				worst.offset = std::max(worst.offset, std::abs(err.offset));
				worst.tiltDeg = std::max(worst.tiltDeg, err.tiltDeg);
			}
		std::printf("scene %s estimates %zu in_force_at_10_kf_from_kf %ld offset_10kf_cm %.2f tilt_10kf_deg %.2f worst_from_10kf_offset_cm %.2f "
					"worst_from_10kf_tilt_deg %.2f final_offset_cm %.2f final_tilt_deg %.2f\n",
					name.c_str(), estimates.size() - 1, at10->keyframes, 100 * e10.offset, e10.tiltDeg, 100 * worst.offset,
					worst.tiltDeg, 100 * last.offset, last.tiltDeg);
		return 0;
	}
	catch (const std::exception& ex)
	{
		std::fprintf(stderr, "keygrid_floor_estimate_eval: %s\n", ex.what());
		return 1;
	}
}

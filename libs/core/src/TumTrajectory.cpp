#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/TumTrajectory.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace keygrid::core
{
Trajectory readTumTrajectory(
	const std::string& path, const TrajectoryReadOptions& opts, std::vector<TextLineIssue>* issues)
{
	std::vector<std::pair<StampedPose, std::size_t>> rows;  // pose, line
	for (const auto& rec : readTumTextRecords(path))
	{
		auto bad = [&](const std::string& why) {
			TextLineIssue is{path, rec.line, why};
			if (!opts.skipBadLines) throw std::runtime_error(is.str());
			if (issues) issues->push_back(is);
		};
		if (rec.fields.size() != 8)
		{
			bad("expected 8 fields 't tx ty tz qx qy qz qw', got " + std::to_string(rec.fields.size()));
			continue;
		}
		double v[8];
		int badField = -1;
		for (int i = 0; i < 8 && badField < 0; i++)
			if (!parseDouble(rec.fields[i], v[i])) badField = i;
		if (badField >= 0)
		{
			bad("field " + std::to_string(badField + 1) + " '" + rec.fields[badField] +
				"' is not a finite number");
			continue;
		}
		const double qn = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
		if (std::abs(qn - 1.0) > opts.quaternionNormTolerance)
		{
			bad("quaternion norm " + std::to_string(qn) + " is not 1");
			continue;
		}
		// MRPT's CQuaternion takes (w, x, y, z).
		mrpt::math::CQuaternionDouble q(v[7] / qn, v[4] / qn, v[5] / qn, v[6] / qn);
		StampedPose sp;
		sp.t = v[0];
		sp.T_world_cam = mrpt::poses::CPose3D(mrpt::poses::CPose3DQuat(v[1], v[2], v[3], q));
		rows.emplace_back(sp, rec.line);
	}
	// Sorted by time (a stable sort keeps the file's order among equal stamps); a repeated stamp
	// is named on the line that repeats it.
	std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first.t < b.first.t; });
	Trajectory out;
	out.reserve(rows.size());
	for (std::size_t i = 0; i < rows.size(); i++)
	{
		if (i > 0 && rows[i].first.t == rows[i - 1].first.t)
		{
			char t[64];
			std::snprintf(t, sizeof(t), "%.6f", rows[i].first.t);
			TextLineIssue is{path, rows[i].second, "repeated timestamp " + std::string(t) + " (first on line " + std::to_string(rows[i - 1].second) + ")"};
			if (!opts.skipBadLines) throw std::runtime_error(is.str());
			if (issues) issues->push_back(is);
			rows[i].second = rows[i - 1].second;  // a third repeat names the first line too
			continue;
		}
		out.push_back(rows[i].first);
	}
	return out;
}

std::string tumLine(const StampedPose& p)
{
	const mrpt::poses::CPose3DQuat q(p.T_world_cam);
	char buf[256];
	std::snprintf(
		buf, sizeof(buf), "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f", p.t, q.x(), q.y(), q.z(),
		q.quat().x(), q.quat().y(), q.quat().z(), q.quat().r());
	return buf;
}

void writeTumTrajectory(const std::string& path, const Trajectory& traj, const std::string& header)
{
	writeFileAtomically(path, [&](std::ostream& f) {
		f << "# " << (header.empty() ? "keygrid trajectory" : header) << "\n";
		f << "# timestamp tx ty tz qx qy qz qw  (T_world_cam, optical frame)\n";
		for (const auto& p : traj) f << tumLine(p) << "\n";
	});
}

}  // namespace keygrid::core

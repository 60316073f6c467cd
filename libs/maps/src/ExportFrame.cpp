#include <keygrid/maps/ExportFrame.h>
#include <mrpt/math/CQuaternion.h>

#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
std::string floorFrameComment(const mrpt::poses::CPose3D& T_world_floor)
{
	mrpt::math::CQuaternionDouble q;
	T_world_floor.getAsQuaternion(q);
	char buf[256];
	std::snprintf(buf, sizeof(buf), "keygrid T_world_floor (x y z qx qy qz qw): %.9g %.9g %.9g %.9g %.9g %.9g %.9g",
				  T_world_floor.x(), T_world_floor.y(), T_world_floor.z(), q.x(), q.y(), q.z(), q.r());
	return buf;
}

std::optional<mrpt::poses::CPose3D> floorFrameFromComment(const std::string& line)
{
	const std::string tag = "keygrid T_world_floor";
	const auto at = line.find(tag);
	if (at == std::string::npos || line.find_first_not_of("#comment \t") < at) return std::nullopt;
	const auto colon = line.find(':', at);
	if (colon == std::string::npos) return std::nullopt;
	double v[7];
	std::istringstream is(line.substr(colon + 1));
	if (!(is >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5] >> v[6])) return std::nullopt;
	return mrpt::poses::CPose3D(mrpt::math::CQuaternionDouble(v[6], v[3], v[4], v[5]), v[0], v[1], v[2]);
}

std::string poseMatrixText(const mrpt::poses::CPose3D& p)
{
	const auto R = p.getRotationMatrix();
	std::string out;
	char buf[32];
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++)
		{
			std::snprintf(buf, sizeof(buf), "%s%.17g", out.empty() ? "" : " ", c < 3 ? R(r, c) : p.m_coords[r]);
			out += buf;
		}
	return out;
}

mrpt::poses::CPose3D poseFromMatrixText(const std::string& text)
{
	std::istringstream in(text);
	mrpt::math::CMatrixDouble33 R;
	mrpt::math::CVectorFixedDouble<3> t;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++)
			if (!(in >> (c < 3 ? R(r, c) : t[r])))
				throw std::invalid_argument("pose '" + text + "': expected the 12 numbers of a 3x4 matrix [R | t], row by row");
	std::string rest;
	if (in >> rest) throw std::invalid_argument("pose '" + text + "': more than 12 numbers");
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}

ExportFrame floorExportFrame(const mrpt::poses::CPose3D& T_world_floor)
{
	ExportFrame f;
	f.T_out_world = -T_world_floor;
	f.comment = floorFrameComment(T_world_floor);
	return f;
}

}  // namespace keygrid::maps

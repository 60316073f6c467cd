#include <keygrid/maps/ExportFrame.h>
#include <mrpt/math/CQuaternion.h>

#include <cstdio>

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

ExportFrame floorExportFrame(const mrpt::poses::CPose3D& T_world_floor)
{
	ExportFrame f;
	f.T_out_world = -T_world_floor;
	f.comment = floorFrameComment(T_world_floor);
	return f;
}

}  // namespace keygrid::maps

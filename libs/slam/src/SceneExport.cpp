#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/slam/SceneExport.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/rtti/CObject.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace keygrid::slam
{
namespace
{
/** A new T created by MRPT's class factory, i.e. inside libmrpt-opengl. For classes with two
 * shader bases (CSetOfLines, CFrustum) GCC places the over-aligned second base at a 16-byte
 * offset; constructing or destroying them in our (UBSan-instrumented) code is reported as a
 * misaligned member call, so their construction and destruction stay in the library. */
template <class T>
typename T::Ptr createInMrpt()
{
	auto obj = std::dynamic_pointer_cast<T>(mrpt::rtti::classFactory(T::GetRuntimeClassIdStatic().className));
	if (!obj) throw std::logic_error(std::string("MRPT class factory cannot create ") + T::GetRuntimeClassIdStatic().className);
	return obj;
}

/** Pose that shows the world with +Z up (see header). */
mrpt::poses::CPose3D displayFromWorld(const std::optional<mrpt::poses::CPose3D>& T_world_floor)
{
	if (T_world_floor) return -*T_world_floor;  // p_floor = inv(T_world_floor) * p_world
	return core::T_depth_cam();  // p_mrpt = T_depth_cam * p_cam
}

/** Moves a map's visualization from world to display coordinates. Point clouds are
 * transformed point by point, so that a colour-by-height (enableColorFromZ) follows the
 * display's +Z (up) instead of the world's z; other objects are re-posed. */
void toDisplayFrame(mrpt::opengl::CSetOfObjects& objs, const mrpt::poses::CPose3D& T_display_world)
{
	for (auto& o : objs)
	{
		auto* pc = dynamic_cast<mrpt::opengl::CPointCloud*>(o.get());
		if (pc && o->getPoseRef() == mrpt::poses::CPose3D())
		{
			const std::size_t n = pc->size();
			std::vector<float> x(n), y(n), z(n);
			for (std::size_t k = 0; k < n; k++)
			{
				const auto& p = pc->getPoint3Df(k);
				const auto q = T_display_world.composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z));
				x[k] = static_cast<float>(q.x);
				y[k] = static_cast<float>(q.y);
				z[k] = static_cast<float>(q.z);
			}
			pc->setAllPoints(x, y, z);
		}
		else
			o->setPose(T_display_world + o->getPoseRef());
	}
}

mrpt::opengl::CSetOfLines::Ptr trajectoryLine(const core::Trajectory& traj, float width)
{
	auto line = createInMrpt<mrpt::opengl::CSetOfLines>();
	line->setName("trajectory");
	line->setLineWidth(width);
	line->setColor_u8(230, 60, 30);
	auto centre = [](const core::StampedPose& p) {
		return mrpt::math::TPoint3D(p.T_world_cam.x(), p.T_world_cam.y(), p.T_world_cam.z());
	};
	if (traj.size() == 1) line->appendLine(centre(traj[0]), centre(traj[0]));
	for (std::size_t i = 1; i < traj.size(); i++) line->appendLine(centre(traj[i - 1]), centre(traj[i]));
	return line;
}

mrpt::opengl::CSetOfObjects::Ptr keyframeFrustums(const sfm::SparseMap& map, double depth)
{
	auto kfs = mrpt::opengl::CSetOfObjects::Create();
	kfs->setName("keyframes");
	for (const auto& [id, kf] : map.keyframes())
	{
		const auto& cam = kf.features.camera;
		// CFrustum's axis is +X (MRPT convention): place it at the depth-sensor pose.
		const double hfov = 2 * std::atan2(0.5 * cam.width, cam.fx), vfov = 2 * std::atan2(0.5 * cam.height, cam.fy);
		auto fr = createInMrpt<mrpt::opengl::CFrustum>();
		fr->setNearFarPlanes(0.0f, static_cast<float>(depth));
		fr->setHorzFOV(static_cast<float>(mrpt::RAD2DEG(hfov)));
		fr->setVertFOV(static_cast<float>(mrpt::RAD2DEG(vfov)));
		fr->setPose(core::sensorPoseFromCameraPose(kf.T_world_cam));
		fr->setColor_u8(40, 90, 220);
		fr->setName("kf_" + std::to_string(id));
		kfs->insert(fr);
	}
	return kfs;
}

mrpt::opengl::CPointCloud::Ptr landmarkCloud(const sfm::SparseMap& map, float pointSize)
{
	auto pc = mrpt::opengl::CPointCloud::Create();
	pc->setName("landmarks");
	pc->setPointSize(pointSize);
	pc->setColor_u8(20, 20, 20);
	for (const auto& [id, lm] : map.landmarks())
		pc->insertPoint(static_cast<float>(lm.p_world.x()), static_cast<float>(lm.p_world.y()), static_cast<float>(lm.p_world.z()));
	return pc;
}
}  // namespace

mrpt::opengl::COpenGLScene::Ptr buildRunScene(
	const core::Trajectory& trajectory, const sfm::SparseMap& map, const mrpt::maps::CMultiMetricMap* maps,
	const std::optional<mrpt::poses::CPose3D>& T_world_floor, const SceneExportOptions& opts)
{
	auto scene = mrpt::opengl::COpenGLScene::Create();
	auto ground = mrpt::opengl::CGridPlaneXY::Create(-10, 10, -10, 10, 0, 1);
	ground->setName("ground");
	ground->setColor_u8(160, 160, 160, 120);
	scene->insert(ground);

	auto run = mrpt::opengl::CSetOfObjects::Create();
	run->setName("keygrid_run");
	const mrpt::poses::CPose3D T_display_world = displayFromWorld(T_world_floor);
	run->setPose(T_display_world);
	run->insert(trajectoryLine(trajectory, opts.trajectoryLineWidth));
	run->insert(keyframeFrustums(map, opts.frustumDepth));
	run->insert(landmarkCloud(map, opts.landmarkPointSize));
	scene->insert(run);
	if (maps)
	{
		std::size_t i = 0;
		for (const auto& m : maps->maps)
		{
			auto objs = mrpt::opengl::CSetOfObjects::Create();
			m->getVisualizationInto(*objs);
			objs->setName("map_" + std::to_string(i++) + "_" + m->GetRuntimeClass()->className);
			toDisplayFrame(*objs, T_display_world);
			scene->insert(objs);
		}
	}
	return scene;
}

void writeRunScene(
	const core::Trajectory& trajectory, const sfm::SparseMap& map, const mrpt::maps::CMultiMetricMap* maps,
	const std::optional<mrpt::poses::CPose3D>& T_world_floor, const std::string& path, const SceneExportOptions& opts)
{
	core::saveGzAtomically(*buildRunScene(trajectory, map, maps, T_world_floor, opts), path);
}

}  // namespace keygrid::slam

#include <keygrid/maps/OctomapBinaryReader.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/slam/apps/Grid3DEvaluation.h>
#include <keygrid/slam/apps/KeyFrameViews.h>
#include <mrpt/system/filesystem.h>

#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
/** The map's frame in the ground-truth world: T_gt_est composed with T_est_map. */
eval::Similarity3 mapInGroundTruth(const eval::Similarity3& T_gt_est, const mrpt::poses::CPose3D& T_est_map)
{
	eval::Similarity3 T = T_gt_est;
	T.R = T_gt_est.R * T_est_map.getRotationMatrix().asEigen();
	T.t = T_gt_est.apply(Eigen::Vector3d(T_est_map.x(), T_est_map.y(), T_est_map.z()));
	return T;
}

/** Marks the true voxels under every pixel's surface point within maxRange. */
void markSeenVoxels(
	eval::VoxelTruth& truth, const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam,
	double maxRange)
{
	const auto K = cam.pinhole();
	const auto R = T_world_cam.getRotationMatrix().asEigen();
	const Eigen::Vector3d t(T_world_cam.x(), T_world_cam.y(), T_world_cam.z());
	for (int v = 0; v < depth.rows; v++)
	{
		const float* row = depth.ptr<float>(v);
		for (int u = 0; u < depth.cols; u++)
		{
			if (!(row[u] > 0)) continue;
			const Eigen::Vector3d p_cam = K.backProject(double(u), double(v), double(row[u]));
			if (p_cam.norm() > maxRange) continue;
			truth.markSeen(R * p_cam + t);
		}
	}
}
}  // namespace

bool Grid3DEvaluationOptions::isValid(std::string* error) const
{
	std::string why;
	if (!metrics.isValid(&why)) why = "tolerance: " + why;
	else if (!(maxRange > 0)) why = "maxRange must be > 0 m (got " + std::to_string(maxRange) + ")";
	else if (scenePath.empty() != keyframesPath.empty()) why = "the seen mask needs both a scene and a keyframes file";
	if (error) *error = why;
	return why.empty();
}

Grid3DEvaluationResult evaluateGrid3DAgainstVoxels(
	const Grid3DEvaluationOptions& o, const eval::Similarity3& T_gt_est, const core::Trajectory& gtTraj)
{
	std::string why;
	if (!o.isValid(&why)) throw std::invalid_argument("3D grid evaluation: " + why);
	for (const auto& p : {o.gridBt, o.voxelsPath})
		if (!mrpt::system::fileExists(p)) throw std::runtime_error("'" + p + "' does not exist");
	const maps::OctomapBinaryVoxels bt = maps::readOctomapBinary(o.gridBt);
	const sim::VoxelSet gtVoxels = sim::VoxelSet::load(o.voxelsPath);

	Grid3DEvaluationResult r;
	r.resolution = bt.resolution;
	r.scale = T_gt_est.s;
	r.floorFrame = bt.T_world_floor.has_value();
	eval::VoxelMapEstimate est;
	est.resolution = bt.resolution;
	est.occupied.assign(bt.occupied.begin(), bt.occupied.end());
	est.free.assign(bt.free.begin(), bt.free.end());
	eval::VoxelTruth truth(gtVoxels.resolution(), gtVoxels.origin(), {gtVoxels.voxels().begin(), gtVoxels.voxels().end()});

	if (!o.scenePath.empty())
	{
		KeyFrameViewsOptions views;
		views.scenePath = o.scenePath;
		views.keyframesPath = o.keyframesPath;
		views.maxDt = o.maxDt;
		views.progress = o.progress;
		r.visibilityKeyframes = renderKeyFrameViews(
			views, gtTraj, [&](const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam) {
				markSeenVoxels(truth, depth, cam, T_world_cam, o.maxRange);
			});
	}
	const auto T_gt_map = mapInGroundTruth(T_gt_est, bt.T_world_floor.value_or(mrpt::poses::CPose3D()));
	r.metrics = eval::evaluateVoxelMap(est, T_gt_map, truth, o.metrics);
	return r;
}

std::string Grid3DEvaluationResult::toText() const
{
	std::ostringstream o;
	o << "3D grid vs true voxels (voxels of " << resolution;
	if (scale != 1) o << " map units = " << resolution * scale << " m";
	else o << " m";
	o << ", " << (floorFrame ? "floor frame" : "SLAM world frame") << ", "
	  << (visibilityKeyframes ? "seen from " + std::to_string(visibilityKeyframes) + " keyframes"
							  : std::string("no seen mask: every true voxel counts as seen"))
	  << "):\n"
	  << metrics.toText();
	return o.str();
}

std::string Grid3DEvaluationResult::jsonFields() const
{
	std::ostringstream o;
	o << metrics.jsonFields("grid3d_") << ",\n"
	  << "  \"grid3d_resolution\": " << resolution << ",\n"
	  << "  \"grid3d_voxel_size_m\": " << resolution * scale << ",\n"
	  << "  \"grid3d_floor_frame\": " << (floorFrame ? "true" : "false") << ",\n"
	  << "  \"grid3d_visibility_keyframes\": " << visibilityKeyframes;
	return o.str();
}

}  // namespace keygrid::slam

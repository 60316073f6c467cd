#include <keygrid/slam/System.h>

#include <chrono>

namespace keygrid::slam
{
namespace
{
double secondsSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

System::System(const SlamConfig& cfg)
	: m_cfg(cfg),
	  m_extractor(cfg.features),
	  m_tracker(m_map, cfg.tracker),
	  m_mapper(m_map, cfg.mapping, cfg.tracker.matcher)
{
}

sfm::FrameFeatures System::extract(const core::Frame& frame) const { return m_extractor.extract(frame); }

const sfm::TrackedFrame& System::process(const core::Frame& frame)
{
	const auto t0 = std::chrono::steady_clock::now();
	auto f = extract(frame);
	m_timings.add("extract", secondsSince(t0));
	return processExtracted(frame, std::move(f));
}

const sfm::TrackedFrame& System::processExtracted(const core::Frame& frame, sfm::FrameFeatures features)
{
	auto t0 = std::chrono::steady_clock::now();
	const sfm::PinholeIntrinsics K = sfm::intrinsicsOf(features.camera);
	sfm::TrackedFrame tf = m_tracker.track(frame, std::move(features));
	m_timings.add("track", secondsSince(t0));
	if (tf.newKeyFrame)
	{
		t0 = std::chrono::steady_clock::now();
		const auto rep = m_mapper.process(tf.keyframe, K);
		m_timings.add("local_mapping", secondsSince(t0));
		m_stats.keyframesCreated++;
		m_stats.keyframesCulled += rep.culledKeyFrames;
		m_stats.landmarksCulled += rep.culledLandmarks;
		m_stats.landmarksFused += rep.fusedLandmarks;
	}
	m_stats.frames++;
	if (tf.tracked) m_stats.tracked++;
	else
		m_stats.lost++;
	if (tf.method == "relocalization" && tf.tracked) m_stats.relocalizations++;
	if (tf.method == "pnp" && tf.tracked) m_stats.pnpFallbacks++;
	m_frames.push_back(std::move(tf));
	return m_frames.back();
}

core::Trajectory System::trajectory() const
{
	core::Trajectory out;
	out.reserve(m_frames.size());
	for (const auto& f : m_frames)
	{
		mrpt::poses::CPose3D T_world_ref;
		if (f.hasReference && m_map.poseOf(f.reference, T_world_ref))
			out.push_back({f.timestamp, T_world_ref + f.T_ref_cam});
		else
			out.push_back({f.timestamp, f.T_world_cam});
	}
	return out;
}

core::Trajectory System::keyframeTrajectory() const
{
	core::Trajectory out;
	for (const auto& [id, kf] : m_map.keyframes()) out.push_back({kf.timestamp, kf.T_world_cam});
	return out;
}

}  // namespace keygrid::slam

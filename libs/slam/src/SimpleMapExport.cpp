#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdio>
#include <stdexcept>

namespace keygrid::slam
{
mrpt::maps::CSimpleMap keyframesSimpleMap(const sfm::SparseMap& map)
{
	mrpt::maps::CSimpleMap sm;
	for (const auto& [id, kf] : map.keyframes())
	{
		if (kf.depth.empty() || kf.colour.empty()) continue;
		core::Frame f;
		f.index = kf.frameIndex;
		f.timestamp = kf.timestamp;
		f.depth = kf.depth;
		if (kf.colour.channels() == 3)
			f.colour = kf.colour;
		else
			f.grey = kf.colour;
		f.camera = kf.features.camera;
		core::ObservationWriteOptions wo;
		wo.sensorLabel = "KEYFRAME";
		auto obs = core::makeRgbdObservation(f, wo);
		auto sf = mrpt::obs::CSensoryFrame::Create();
		sf->insert(obs);
		// Robot pose = depth-sensor pose T_world_depth, sensorPose = identity (see header);
		// zero covariance: only the mean is known.
		auto T_world_depth = mrpt::poses::CPose3DPDFGaussian::Create();
		T_world_depth->mean = core::sensorPoseFromCameraPose(kf.T_world_cam);
		sm.insert(T_world_depth, sf);
	}
	return sm;
}

void saveGzAtomically(const mrpt::serialization::CSerializable& obj, const std::string& path)
{
	const std::string tmp = path + ".tmp";
	try
	{
		mrpt::io::CFileGZOutputStream f;
		if (!f.open(tmp)) throw std::runtime_error("cannot write '" + path + "'");
		mrpt::serialization::archiveFrom(f) << obj;
		f.close();
	}
	catch (const std::exception& e)
	{
		std::remove(tmp.c_str());
		throw std::runtime_error("error while writing '" + path + "': " + e.what());
	}
	if (std::rename(tmp.c_str(), path.c_str()) != 0)
	{
		std::remove(tmp.c_str());
		throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "'");
	}
}

std::size_t writeKeyframesSimpleMap(const sfm::SparseMap& map, const std::string& path)
{
	const auto sm = keyframesSimpleMap(map);
	saveGzAtomically(sm, path);
	return sm.size();
}

}  // namespace keygrid::slam

#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace keygrid::slam
{
mrpt::maps::CSimpleMap::Pair keyframeSimpleMapEntry(const sfm::KeyFrame& kf, const KeyFrameImageData& img)
{
	core::Frame f;
	f.index = kf.frameIndex;
	f.timestamp = kf.timestamp;
	f.depth = img.depth;
	if (img.colour.channels() == 3)
		f.colour = img.colour;
	else
		f.grey = img.colour;
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
	mrpt::maps::CSimpleMap::Pair p;
	p.pose = T_world_depth;
	p.sf = sf;
	return p;
}

mrpt::maps::CSimpleMap keyframesSimpleMap(const sfm::SparseMap& map, const KeyFrameImageSource& images)
{
	mrpt::maps::CSimpleMap sm;
	for (const auto& [id, kf] : map.keyframes())
	{
		if (!images.hasImages(kf)) continue;
		const auto e = keyframeSimpleMapEntry(kf, images.load(kf));
		sm.insert(e.pose, e.sf);
	}
	return sm;
}

namespace
{
/** The bytes CArchive writes around a CSimpleMap's content, taken from an empty map's
 * serialization: the object header (class name, version), then the content (CSimpleMap
 * version 1: uint32 entry count, then each entry's pose PDF and sensory frame as objects), then
 * the end-of-object marker. */
struct SimpleMapFraming
{
	std::vector<std::uint8_t> head, tail;
};

SimpleMapFraming simpleMapFraming()
{
	mrpt::io::CMemoryStream mem;
	mrpt::serialization::archiveFrom(mem) << mrpt::maps::CSimpleMap();
	const auto* b = static_cast<const std::uint8_t*>(mem.getRawBufferData());
	const std::size_t n = mem.getTotalBytesCount();
	constexpr std::size_t kCount = sizeof(std::uint32_t), kTail = 1;
	// The header ends with the version byte: 1, the format of the entries written below.
	bool ok = n > kCount + kTail + 1 && b[n - kCount - kTail - 1] == 1;
	for (std::size_t i = n - kCount - kTail; ok && i < n - kTail; i++) ok = b[i] == 0;
	if (!ok) throw std::logic_error("CSimpleMap's serialization is not the one keyframes.simplemap streaming writes (MRPT version?)");
	return {std::vector<std::uint8_t>(b, b + n - kCount - kTail), std::vector<std::uint8_t>(b + n - kTail, b + n)};
}
}  // namespace

std::size_t writeKeyframesSimpleMap(const sfm::SparseMap& map, const KeyFrameImageSource& images, const std::string& path)
{
	std::vector<const sfm::KeyFrame*> entries;
	for (const auto& [id, kf] : map.keyframes())
		if (images.hasImages(kf)) entries.push_back(&kf);
	const auto framing = simpleMapFraming();
	core::writeGzAtomically(path, [&](mrpt::io::CStream& out) {
		auto a = mrpt::serialization::archiveFrom(out);
		a.WriteBuffer(framing.head.data(), framing.head.size());
		a.WriteAs<uint32_t>(entries.size());
		for (const sfm::KeyFrame* kf : entries)
		{
			const auto e = keyframeSimpleMapEntry(*kf, images.load(*kf));
			a << *e.pose << *e.sf;
		}
		a.WriteBuffer(framing.tail.data(), framing.tail.size());
	});
	return entries.size();
}

}  // namespace keygrid::slam

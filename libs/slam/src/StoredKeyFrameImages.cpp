#include <keygrid/slam/StoredKeyFrameImages.h>
#include <keygrid/store/KeyFrameImageCodec.h>

namespace keygrid::slam
{
bool StoredKeyFrameImages::hasImages(const sfm::KeyFrame& kf) const
{
	const auto enc = m_session.loadEncodedImages(kf.id);
	return !enc.colour.empty() && !enc.depth.empty();
}

KeyFrameImageData StoredKeyFrameImages::load(const sfm::KeyFrame& kf) const
{
	const auto img = m_session.loadImages(kf.id);
	KeyFrameImageData out;
	out.colour = img.colour;
	if (!img.depthRaw.empty()) out.depth = store::KeyFrameImageCodec::rawToDepth(img.depthRaw, kf.features.camera.depthUnits);
	return out;
}

}  // namespace keygrid::slam

#pragma once
/** \file StoredKeyFrameImages.h
 * The keyframe images of a session file (store::SessionStore::loadImages), decoded to what
 * sfm::KeyFrame holds (depth in metres with the keyframe camera's depth units).
 */
#include <keygrid/slam/KeyFrameImageSource.h>
#include <keygrid/store/SessionStore.h>

namespace keygrid::slam
{
class StoredKeyFrameImages : public KeyFrameImageSource
{
   public:
	/** `session` must outlive this object. */
	explicit StoredKeyFrameImages(const store::SessionStore& session) : m_session(session) {}
	/** Reads the encoded images (no decoding). */
	bool hasImages(const sfm::KeyFrame& kf) const override;
	KeyFrameImageData load(const sfm::KeyFrame& kf) const override;

   private:
	const store::SessionStore& m_session;
};

}  // namespace keygrid::slam

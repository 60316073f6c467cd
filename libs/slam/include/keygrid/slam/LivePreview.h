#pragma once
/** \file LivePreview.h
 * The live run's preview: the current image with its keypoints (yellow) and the keypoints
 * tracked against the map (green), and a status line, in an MRPT CDisplayWindow.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/sfm/Tracker.h>

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace keygrid::slam
{
class LivePreview
{
   public:
	/** Opens the window (needs a display: see displayAvailable()). */
	explicit LivePreview(const std::string& title);
	~LivePreview();

	/** Shows `frame` annotated (see render()). */
	void show(
		const core::Frame& frame, const std::vector<cv::KeyPoint>& keypoints,
		const sfm::TrackedFrame& tracked, const std::string& status);

	/** True once the user closed the window. */
	bool closed() const;

	/** The annotated BGR image show() displays (no window needed). */
	static cv::Mat render(
		const core::Frame& frame, const std::vector<cv::KeyPoint>& keypoints,
		const sfm::TrackedFrame& tracked, const std::string& status);

	/** Whether a window can be opened: an X display is named in $DISPLAY. */
	static bool displayAvailable();

   private:
	struct Impl;
	std::unique_ptr<Impl> m_impl;
};

}  // namespace keygrid::slam

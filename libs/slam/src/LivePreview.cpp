#include <keygrid/slam/LivePreview.h>
#include <mrpt/gui/CDisplayWindow.h>
#include <mrpt/img/CImage.h>
#include <opencv2/imgproc.hpp>

#include <cstdlib>

namespace keygrid::slam
{
struct LivePreview::Impl
{
	mrpt::gui::CDisplayWindow::Ptr window;
};

LivePreview::LivePreview(const std::string& title) : m_impl(std::make_unique<Impl>())
{
	m_impl->window = mrpt::gui::CDisplayWindow::Create(title, 640, 480);
}

LivePreview::~LivePreview() = default;

bool LivePreview::displayAvailable()
{
	const char* d = std::getenv("DISPLAY");
	return d && *d;
}

bool LivePreview::closed() const { return !m_impl->window || !m_impl->window->isOpen(); }

cv::Mat LivePreview::render(
	const core::Frame& frame, const std::vector<cv::KeyPoint>& keypoints, const sfm::TrackedFrame& tracked,
	const std::string& status)
{
	cv::Mat img;
	if (!frame.colour.empty())
		img = frame.colour.clone();
	else if (!frame.grey.empty())
		cv::cvtColor(frame.grey, img, cv::COLOR_GRAY2BGR);
	else
		img = cv::Mat::zeros(480, 640, CV_8UC3);
	for (const auto& kp : keypoints) cv::circle(img, kp.pt, 2, cv::Scalar(0, 220, 255), 1, cv::LINE_8);
	// Tracked inliers are stored undistorted: close enough to the raw image for a preview.
	for (const auto& ob : tracked.observations)
		cv::circle(img, cv::Point2f(ob.u, ob.v), 3,
				   cv::Scalar(0, 255, 0), 2, cv::LINE_8);
	const cv::Scalar textColour = tracked.tracked ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255);
	cv::rectangle(img, cv::Point(0, 0), cv::Point(img.cols, 22), cv::Scalar(0, 0, 0), cv::FILLED);
	cv::putText(img, status, cv::Point(5, 16), cv::FONT_HERSHEY_SIMPLEX, 0.45, textColour, 1, cv::LINE_AA);
	return img;
}

void LivePreview::show(
	const core::Frame& frame, const std::vector<cv::KeyPoint>& keypoints, const sfm::TrackedFrame& tracked,
	const std::string& status)
{
	if (closed()) return;
	m_impl->window->showImage(mrpt::img::CImage(render(frame, keypoints, tracked, status), mrpt::img::SHALLOW_COPY));
}

}  // namespace keygrid::slam

#include <keygrid/core/Frame.h>
#include <opencv2/imgproc.hpp>

namespace keygrid::core
{
bool setFrameImages(const cv::Mat& img, Frame& out)
{
	if (img.channels() == 3)
	{
		out.colour = img.clone();
		cv::cvtColor(img, out.grey, cv::COLOR_BGR2GRAY);
		return true;
	}
	if (img.channels() == 1)
	{
		out.colour.release();
		out.grey = img.clone();
		return true;
	}
	return false;
}

bool setImageOnlyFrame(const cv::Mat& image, double timestamp, const RgbdCamera& camera, Frame& out)
{
	if (!setFrameImages(image, out)) return false;
	out.timestamp = timestamp;
	out.camera = camera;
	out.depth.release();
	out.depthRaw.release();
	return true;
}

}  // namespace keygrid::core

#pragma once
/** \file OpenNI2FrameSource.h
 * Frames from a Kinect / Xtion (any OpenNI2 device) through MRPT's COpenNI2Sensor.
 *
 * The device is configured by the same keys rawlog-grabber's COpenNI2Sensor section takes
 * (device_number, serial_number, width, height, fps, sensorLabel, optional <section>_LEFT /
 * _RIGHT / _LEFT2RIGHT_POSE calibration), read from one INI section (keygrid-slam: [live]),
 * plus the OpenNI2SourceOptions keys below in the same section.
 */
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/RgbdCamera.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::slam
{
struct OpenNI2SourceOptions
{
	/** Seconds an open device may deliver no frame before next() fails (Default: 5 s) */
	double frameTimeout{5.0};
	/** Sleep between polls of the device while no new frame is ready [s] (Default: 0.002 s) */
	double pollPeriod{0.002};
	/** The device registers depth to the colour camera in hardware (OpenNI2's
	 * DEPTH_TO_COLOR mode, what MRPT's driver asks for): depth and image share the colour
	 * intrinsics. false = register in software from the observation's two calibrations
	 * (Default: true) */
	bool depthRegistered{true};
	/** Intrinsics to use instead of the device's factory values, e.g. a calibrated camera INI
	 * ([slam] camera in keygrid-slam; Default: none = the device's) */
	std::optional<core::RgbdCamera> camera;

	/** Reads frame_timeout, poll_period and depth_registered from `section`; invalid values
	 * throw std::invalid_argument naming the key and value. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
};

class OpenNI2FrameSource : public core::FrameSource
{
   public:
	/** Loads the sensor configuration from `section` of `ini` and opens the device. Throws
	 * std::runtime_error("no OpenNI2 device found (...)") when none is connected, or MRPT's
	 * reason when the device cannot be opened. */
	OpenNI2FrameSource(
		const mrpt::config::CConfigFileBase& ini, const std::string& section,
		const OpenNI2SourceOptions& opts);
	~OpenNI2FrameSource() override;

	/** Blocks until the device delivers a frame (false after cancel()). Throws on a hardware
	 * error or when no frame came for frameTimeout seconds. Observations that cannot be
	 * frames are skipped and counted. */
	bool next(core::Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return std::nullopt; }
	std::string describe() const override { return m_describe; }

	/** Makes a waiting next() return false (thread-safe). */
	void cancel() { m_cancel.store(true); }

	/** Number of OpenNI2 devices connected right now (0 without a device or driver). */
	static int connectedDevices();

   private:
	struct Impl;
	std::unique_ptr<Impl> m_impl;
	OpenNI2SourceOptions m_opts;
	std::string m_describe;
	std::atomic<bool> m_cancel{false};
	std::size_t m_nextIndex{0};
};

}  // namespace keygrid::slam

#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/slam/OpenNI2FrameSource.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/hwdrivers/COpenNI2Generic.h>
#include <mrpt/hwdrivers/COpenNI2Sensor.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace keygrid::slam
{
void OpenNI2SourceOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	frameTimeout = core::readFiniteNumber(c, s, "frame_timeout", frameTimeout);
	pollPeriod = core::readFiniteNumber(c, s, "poll_period", pollPeriod);
	depthRegistered = c.read_bool(s, "depth_registered", depthRegistered);
	if (!(frameTimeout > 0))
		throw std::invalid_argument("[" + s + "] frame_timeout = " + std::to_string(frameTimeout) + " (must be > 0 s)");
	if (!(pollPeriod > 0) || pollPeriod > 1)
		throw std::invalid_argument("[" + s + "] poll_period = " + std::to_string(pollPeriod) + " (must be in (0, 1] s)");
}

void OpenNI2SourceOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "frame_timeout", frameTimeout, 30, 40, "seconds without a frame before the run fails");
	c.write(s, "poll_period", pollPeriod, 30, 40, "seconds between device polls while waiting");
	c.write(s, "depth_registered", depthRegistered, 30, 40, "depth registered to colour by the device");
}

struct OpenNI2FrameSource::Impl
{
	// MRPT 2.5's ~COpenNI2Sensor() closes its device and throws when there is none (e.g. it was
	// unplugged): see the destructor below.
	std::unique_ptr<mrpt::hwdrivers::COpenNI2Sensor> sensor;
	int device{0};
};

int OpenNI2FrameSource::connectedDevices()
{
	// A bare COpenNI2Generic enumerates devices and, unlike COpenNI2Sensor, is safe to
	// destroy when none was found.
	mrpt::hwdrivers::COpenNI2Generic probe;
	return probe.getConnectedDevices();
}

OpenNI2FrameSource::OpenNI2FrameSource(
	const mrpt::config::CConfigFileBase& ini, const std::string& section, const OpenNI2SourceOptions& opts)
	: m_impl(std::make_unique<Impl>()), m_opts(opts)
{
	m_impl->device = ini.read_int(section, "device_number", 0);
	if (m_impl->device < 0)
		throw std::invalid_argument("[" + section + "] device_number = " + std::to_string(m_impl->device) + " (must be >= 0)");
	const int found = connectedDevices();
	if (found <= 0)
		throw std::runtime_error(
			"no OpenNI2 device found (is the Kinect/Xtion plugged in and powered, and readable by "
			"this user? check with `lsusb`; a recorded rawlog runs with --input X.rawlog)");
	if (m_impl->device >= found)
		throw std::runtime_error(
			"[" + section + "] device_number = " + std::to_string(m_impl->device) + " but only " +
			std::to_string(found) + " OpenNI2 device(s) are connected");
	m_impl->sensor = std::make_unique<mrpt::hwdrivers::COpenNI2Sensor>();
	m_impl->sensor->loadConfig(ini, section);
	m_impl->sensor->initialize();
	if (!m_impl->sensor->isOpen(static_cast<unsigned>(m_impl->device)))
		throw std::runtime_error("cannot open OpenNI2 device " + std::to_string(m_impl->device));
	const auto& K = m_impl->sensor->getCameraParamsIntensity();
	m_describe = "OpenNI2 device " + std::to_string(m_impl->device) + " '" + m_impl->sensor->getSensorLabel() +
		"' (" + std::to_string(K.ncols) + "x" + std::to_string(K.nrows) + ")";
}

OpenNI2FrameSource::~OpenNI2FrameSource()
{
	// ~COpenNI2Sensor() throws (so std::terminate()s) when its device is gone: leave such a
	// sensor undestroyed (a deliberate, bounded leak at shutdown) rather than abort the run
	// before the outputs are written.
	if (m_impl->sensor && m_impl->sensor->getNumDevices() <= m_impl->device)
		(void)m_impl->sensor.release();
}

bool OpenNI2FrameSource::next(core::Frame& out)
{
	using Clock = std::chrono::steady_clock;
	const auto t0 = Clock::now();
	mrpt::obs::CObservation3DRangeScan obs;
	while (!m_cancel.load())
	{
		bool there = false, hwError = false;
		m_impl->sensor->getNextObservation(obs, there, hwError);
		if (hwError) throw std::runtime_error(m_describe + ": hardware error while grabbing (device unplugged?)");
		if (!there)
		{
			if (std::chrono::duration<double>(Clock::now() - t0).count() > m_opts.frameTimeout)
				throw std::runtime_error(
					m_describe + ": no frame for " + std::to_string(m_opts.frameTimeout) + " s ([live] frame_timeout)");
			std::this_thread::sleep_for(std::chrono::duration<double>(m_opts.pollPeriod));
			continue;
		}
		if (m_opts.depthRegistered)
		{
			// Depth already lies in the colour camera: one set of intrinsics for both.
			if (m_opts.camera) obs.cameraParamsIntensity = m_opts.camera->toTCamera();
			obs.cameraParams = obs.cameraParamsIntensity;
			obs.relativePoseIntensityWRTDepth = core::T_depth_cam();
		}
		std::string why;
		if (!core::frameFromObservation(obs, out, &why))
		{
			noteSkip("OpenNI2 frame " + std::to_string(m_nextIndex) + ": " + why);
			continue;
		}
		if (m_opts.camera && (static_cast<unsigned>(out.grey.cols) != m_opts.camera->width ||
							   static_cast<unsigned>(out.grey.rows) != m_opts.camera->height))
			throw std::runtime_error(
				m_describe + " streams " + std::to_string(out.grey.cols) + "x" + std::to_string(out.grey.rows) +
				" but camera '" + m_opts.camera->name + "' is " + std::to_string(m_opts.camera->width) + "x" +
				std::to_string(m_opts.camera->height) + " (set [live] width/height or [slam] camera)");
		out.index = m_nextIndex++;
		return true;
	}
	return false;
}

}  // namespace keygrid::slam

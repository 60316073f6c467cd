#pragma once
// Private: the per-frame side of a sequence folder (rawlog + TUM layout + masks +
// groundtruth.txt), pipelined: a frame is encoded on a worker while the caller renders the
// next one; its rawlog record and TUM images are encoded in parallel. Files are written in
// frame order, so the bytes do not depend on the schedule.
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/SequenceWriter.h>
#include <keygrid/sim/Simulator.h>

#include <future>
#include <memory>
#include <string>

namespace keygrid::core
{
class RawlogWriter;
}

namespace keygrid::sim
{
class TumFolderWriter;

class SequenceOutput
{
   public:
	/** Creates dir (and dir/tum) and opens the writers the options ask for. */
	SequenceOutput(
		const std::string& dir, const std::string& sceneName, const core::RgbdCamera& camera,
		const OutputOptions& opts);
	~SequenceOutput();

	/** The buffer to fill with the next frame (valid until the second next commit()). */
	SimFrame& next() { return m_buf[m_count % 2]; }
	/** Queues next() for writing (after the previous frame finished; rethrows its errors). */
	void commit();
	/** Waits for the last frame, writes groundtruth.txt (and tum/groundtruth.txt), closes. */
	void close(const std::string& gtHeader);

	std::size_t count() const { return m_count; }

   private:
	std::string m_dir, m_name;
	OutputOptions m_opts;
	std::unique_ptr<core::RawlogWriter> m_rawlog;
	std::unique_ptr<TumFolderWriter> m_tum;
	SimFrame m_buf[2];
	std::future<void> m_pending;
	core::Trajectory m_gt;
	std::size_t m_count{0};
};

/** mkdir -p; throws std::runtime_error naming the directory. */
void makeDirectories(const std::string& dir);

}  // namespace keygrid::sim

#pragma once
/** \file SessionWriter.h
 * Writes a session off the mapping thread. submit() hands over an update and the raw images of
 * its keyframes; a writer thread compresses the images (KeyFrameImageCodec) and commits the
 * update (SessionStore::write), one transaction per update, in submission order. The mapping
 * thread pays for building the update and a queue push; image compression and the commit's
 * fsync happen on the writer thread. A process killed with updates still queued loses those
 * updates only: the file holds every update committed before, each whole.
 */
#include <keygrid/core/BoundedQueue.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>

#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace keygrid::store
{
struct SessionWriterOptions
{
	/** Updates waiting for the writer thread; submit() blocks while the queue is full, which
	 * bounds the memory held by pending images (Default: 8) */
	std::size_t queueCapacity{8};
	/** false: submit() encodes and writes on the calling thread (sequential, deterministic
	 * runs) (Default: true) */
	bool threaded{true};
	/** Compression of the keyframe images */
	ImageCodecOptions images;
};

/** The images of one keyframe as the frontend holds them. The cv::Mat buffers are shared, not
 * copied: do not write into them after submit(). */
struct KeyFrameImageSource
{
	/** CV_8UC3 (BGR) or CV_8UC1; may be empty */
	cv::Mat colour;
	/** CV_16UC1 in raw depth units or CV_32FC1 in metres (converted with depthUnits); may be empty */
	cv::Mat depth;
	/** Metres per raw unit, used for CV_32FC1 depth [m] (Default: 0.0002) */
	float depthUnits{0.0002f};
};

/** One update and the images of its keyframes: images[i] belongs to update.keyframes[i] and is
 * encoded unless update.images[i] already holds encoded images. */
struct SessionWriteJob
{
	SessionUpdate update;
	std::vector<KeyFrameImageSource> images;
};

/** Time spent by the writer, for reports. */
struct SessionWriterStats
{
	std::size_t committed{0};
	/** Total seconds spent compressing images and in SessionStore::write() [s] */
	double encodeSeconds{0}, writeSeconds{0};
};

/** submit(), flush() and close() are for one thread (the mapping thread). */
class SessionWriter
{
   public:
	/** Takes over the store, which must be open for writing (std::invalid_argument otherwise). */
	explicit SessionWriter(SessionStore store, const SessionWriterOptions& opts = {});
	/** Stops the writer after the queued updates. Call close() first to learn about an error:
	 * the destructor cannot report one. */
	~SessionWriter();
	SessionWriter(const SessionWriter&) = delete;
	SessionWriter& operator=(const SessionWriter&) = delete;

	/** Queues a job (blocks while the queue is full). Throws the writer's first error, as
	 * std::runtime_error naming the file, when an earlier update failed; nothing is written
	 * after a failed update. */
	void submit(SessionWriteJob job);
	/** Waits until every submitted update is committed; throws like submit(). */
	void flush();
	/** flush(), then stops the writer thread. Further submit() calls throw std::logic_error. */
	void close();

	SessionWriterStats stats() const;
	const std::string& path() const { return m_path; }

   private:
	void run();
	void process(SessionWriteJob& job);
	void rethrowError();

	SessionStore m_store;
	std::string m_path;
	SessionWriterOptions m_opts;
	KeyFrameImageCodec m_codec;
	core::BoundedQueue<SessionWriteJob> m_queue;
	std::thread m_thread;
	bool m_closed{false};
	mutable std::mutex m_mutex;  //!< guards the fields below
	std::condition_variable m_progress;
	std::size_t m_submitted{0}, m_done{0};
	std::exception_ptr m_error;
	SessionWriterStats m_stats;
};

}  // namespace keygrid::store

#pragma once
/** \file MapOutputFolder.h
 * The folder the maps of a run write their files into (maps::KeyFrameMap::writeOutputs): the
 * frame they are written in, and every file tried even when another failed (a full disk
 * should cost the files that did not fit, not all of them).
 */
#include <keygrid/maps/ExportFrame.h>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace keygrid::maps
{
class MapOutputFolder
{
   public:
	/** Writes into `dir` (which must exist); map points go out mapped into `frame`. */
	MapOutputFolder(std::string dir, ExportFrame frame) : m_dir(std::move(dir)), m_frame(std::move(frame)) {}

	const std::string& dir() const { return m_dir; }
	/** The frame map files are written in (the run's floor frame, else the SLAM world). */
	const ExportFrame& frame() const { return m_frame; }

	/** Writes file `name` with write(dir/name). An exception is recorded, not thrown: the
	 * caller goes on with its other files. Returns whether the file was written. */
	bool write(const std::string& name, const std::function<void(const std::string& path)>& write);
	/** Records a file that a successful write() put beside its own (e.g. a .yaml's .pgm). */
	void noteWritten(const std::string& name) { m_files.push_back(name); }

	/** The files written, in order. */
	const std::vector<std::string>& files() const { return m_files; }
	/** Throws the first failure as a std::runtime_error (naming how many more failed), if any. */
	void throwIfAnyFailed() const;

   private:
	std::string m_dir;
	ExportFrame m_frame;
	std::vector<std::string> m_files;
	std::string m_firstError;
	std::size_t m_failures{0};
};

}  // namespace keygrid::maps

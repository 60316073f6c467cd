#pragma once
/** \file SessionExport.h
 * The usual outputs of a run, written from a stored session (keygrid-map export), also from a
 * session whose run was killed: keyframes.txt (keyframe poses, TUM), the metric maps of the
 * last snapshot (map_2d.*, map_3d.*, hoc_points.*, as keygrid-slam writes them, in the run's
 * floor frame when it had one), hoc_points.ply from the landmarks when no HOC map was
 * snapshotted, and keyframes.simplemap from the stored keyframe images.
 */
#include <string>
#include <vector>

namespace keygrid::slam
{
struct SessionExportResult
{
	std::size_t keyframes{0}, landmarks{0}, simpleMapEntries{0};
	/** Files written into the output folder */
	std::vector<std::string> files;
	/** Snapshots whose maps were written (name, last keyframe they hold) */
	std::vector<std::pair<std::string, std::uint64_t>> snapshots;
};

/** Writes the outputs of session `file` into `dir` (created if missing). Throws
 * std::runtime_error naming the file or folder on failure. */
SessionExportResult exportSession(const std::string& file, const std::string& dir);

}  // namespace keygrid::slam

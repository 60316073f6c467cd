#pragma once
/** \file TumSequence.h
 * Index of a TUM RGB-D folder: the associated (rgb, depth) pairs and the camera.
 * Loading the images is left to TumFrameSource so that only one frame is in memory at a time.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/core/TumText.h>

#include <string>
#include <vector>

namespace keygrid::core
{
struct TumPair
{
	double tRgb{0}, tDepth{0};
	std::string rgbPath, depthPath;  //!< absolute paths
};

/** A timestamped file from rgb.txt / depth.txt. */
struct TumStampedFile
{
	double t{0};
	std::string file;
};

class TumSequence
{
   public:
	/** Indexes `dir`: associations.txt when present, else rgb.txt + depth.txt associated with
	 * |dt| <= maxDt. Malformed lines are skipped and listed in issues(). Throws
	 * std::runtime_error when the folder or its lists are missing or give no pair. */
	TumSequence(const std::string& dir, double maxDt = 0.02);

	const std::string& dir() const { return m_dir; }
	const std::vector<TumPair>& pairs() const { return m_pairs; }
	const std::vector<TextLineIssue>& issues() const { return m_issues; }
	/** "associations.txt" or "rgb.txt+depth.txt" */
	const std::string& indexSource() const { return m_indexSource; }

	/** The camera for this folder: `camera.ini` inside it ([camera] section) if present, else
	 * the preset named by the folder (fr1/freiburg1, fr2, fr3, icl), else "kinect". */
	RgbdCamera guessCamera() const;

   private:
	std::string m_dir;
	std::vector<TumPair> m_pairs;
	std::vector<TextLineIssue> m_issues;
	std::string m_indexSource;
};

}  // namespace keygrid::core

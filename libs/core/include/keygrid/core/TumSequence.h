#pragma once
/** \file TumSequence.h
 * Index of a TUM RGB-D folder: the associated (rgb, depth) pairs and the camera; with depth
 * ignored (monocular input), its colour images alone.
 * Loading the images is left to TumFrameSource so that only one frame is in memory at a time.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/core/TumText.h>

#include <string>
#include <vector>

namespace keygrid::core
{
struct TumPair
{
	double tRgb{0}, tDepth{0};       //!< tDepth = 0 when indexed with depth ignored
	std::string rgbPath, depthPath;  //!< absolute paths; depthPath empty with depth ignored
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
	 * |dt| <= maxDt. With depth = DepthUse::Ignore: every image of rgb.txt (associations.txt's
	 * colour column when there is no rgb.txt), without depth; depth.txt and depth/ need not
	 * exist. Malformed lines are skipped and listed in issues(). Throws std::runtime_error
	 * naming the folder when it or its lists are missing or give no pair (no image). */
	TumSequence(const std::string& dir, double maxDt = 0.02, DepthUse depth = DepthUse::Use);

	const std::string& dir() const { return m_dir; }
	const std::vector<TumPair>& pairs() const { return m_pairs; }
	const std::vector<TextLineIssue>& issues() const { return m_issues; }
	/** "associations.txt" or "rgb.txt+depth.txt"; with depth ignored "rgb.txt" or
	 * "associations.txt" */
	const std::string& indexSource() const { return m_indexSource; }
	/** Whether the pairs carry depth (false when indexed with depth ignored). */
	bool hasDepth() const { return m_hasDepth; }

	/** The camera for this folder: `camera.ini` inside it ([camera] section) if present, else
	 * the preset named by the folder (fr1/freiburg1, fr2, fr3, icl), else "kinect". */
	RgbdCamera guessCamera() const;

   private:
	std::string absolute(const std::string& file) const;
	void indexAssociations(DepthUse depth);
	void indexLists(double maxDt);
	void indexImages();

	std::string m_dir;
	std::vector<TumPair> m_pairs;
	std::vector<TextLineIssue> m_issues;
	std::string m_indexSource;
	bool m_hasDepth{true};
};

}  // namespace keygrid::core

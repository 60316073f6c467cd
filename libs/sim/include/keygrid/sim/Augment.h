#pragma once
/** \file Augment.h
 * Augment mode: renders a scene's objects into a real TUM RGB-D sequence, seen from the
 * sequence's ground-truth poses, with occlusion against the real depth: an object pixel
 * replaces the real one where the real depth is invalid (0) or farther than the object.
 * Object pixels get the scene's sensor model (noise, quantisation, range limits) in the real
 * camera's intrinsics and distortion. The scene's world frame is the sequence's ground-truth
 * world frame; object time t is seconds since the sequence's first frame.
 * Output: the same layout as writeSequence (sequence.rawlog, groundtruth.txt, tum/ with
 * tum/mask/ = inserted pixels), without ground-truth occupancy (the real world has none).
 */
#include <keygrid/sim/SequenceWriter.h>

#include <functional>
#include <optional>
#include <string>

namespace keygrid::core
{
struct RgbdCamera;
}

namespace keygrid::sim
{
class Scene;

struct AugmentOptions
{
	/** Largest gap between a frame and the ground-truth samples around it [s]; frames with no
	 * pose that close are skipped (Default: 0.05 s; TUM ground truth is ~100 Hz) */
	double maxPoseGap{0.05};
	/** Use at most this many frames, 0 = all (Default: 0) */
	std::size_t maxFrames{0};
	/** Camera preset / INI for the TUM folder; empty: TumSequence::guessCamera (Default: empty) */
	std::string camera;
};

struct AugmentSummary
{
	std::size_t frames{0};            //!< frames written
	std::size_t skippedNoPose{0};     //!< frames without ground truth close enough
	double insertedPixelFraction{0};  //!< mean share of pixels showing an inserted object
	double seconds{0};
};

/** Reads tumDir (with groundtruth.txt), writes the augmented sequence to outDir. The scene's
 * camera and trajectory are ignored (the real ones are used). Throws std::runtime_error when
 * the folder, its ground truth or every pose is missing. */
AugmentSummary augmentTumSequence(
	const Scene& objects, const std::string& tumDir, const std::string& outDir,
	const OutputOptions& out, const AugmentOptions& opts = {},
	const std::function<void(std::size_t, std::size_t)>& progress = {}, unsigned threads = 0);

}  // namespace keygrid::sim

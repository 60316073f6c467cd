#pragma once
/** \file Texture.h
 * Procedural, seeded surface textures rich in corners and blobs (rectangles, discs, checker
 * patches of high contrast on a mottled base), so ORB / SIFT find many stable features.
 * A texture is a square tile of `sizeMetres` that repeats over a surface; a small mip pyramid
 * limits aliasing when a surface is seen from far away.
 */
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::sim
{
/** What a surface looks like. */
struct TextureOptions
{
	/** Pattern: "mixed" (rectangles + discs + checker patches), "checker", "blobs" or "plain"
	 * (uniform colour: textureless, for tests only) (Default: "mixed") */
	std::string style{"mixed"};
	/** Seed of the pattern (Default: 1; scenes derive it from the scene seed and object name) */
	std::uint64_t seed{1};
	/** Base colour, B G R in [0, 255] (Default: 150 150 150) */
	std::uint8_t base[3]{150, 150, 150};
	/** Side of one texture tile on the surface [m] (Default: 2.0 m) */
	double sizeMetres{2.0};
	/** Side of the tile image [px], a power of two >= 64 (Default: 1024: ~2 mm per texel) */
	int resolution{1024};

	/** Throws std::invalid_argument naming the field when a value is out of range. */
	void validate() const;
	bool operator==(const TextureOptions& o) const;
};

/** A generated texture with bilinear sampling in surface metres. Immutable once built. */
class Texture
{
   public:
	explicit Texture(const TextureOptions& opts);

	const TextureOptions& options() const { return m_opts; }
	/** Level-0 tile (CV_8UC3, BGR). */
	const cv::Mat& image() const { return m_levels.front(); }
	std::size_t levels() const { return m_levels.size(); }

	/** Colour at surface coordinates (u, v) [m] (the tile repeats), bilinear, from the mip level
	 * whose texel best matches `footprint` (surface metres covered by one camera pixel).
	 * Writes B G R as floats in [0, 255]. */
	void sample(double u, double v, double footprint, float bgr[3]) const;

   private:
	TextureOptions m_opts;
	std::vector<cv::Mat> m_levels;  //!< mip pyramid, level 0 first
	double m_texelMetres{0};
};

}  // namespace keygrid::sim

#include <keygrid/sim/Random.h>
#include <keygrid/sim/Texture.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace keygrid::sim
{
void TextureOptions::validate() const
{
	if (style != "mixed" && style != "checker" && style != "blobs" && style != "plain")
		throw std::invalid_argument(
			"texture = '" + style + "' is not one of mixed, checker, blobs, plain");
	if (!(sizeMetres > 0.01 && sizeMetres < 1000))
		throw std::invalid_argument(
			"texture_size = " + std::to_string(sizeMetres) + " must be in (0.01, 1000) m");
	if (resolution < 64 || resolution > 4096 || (resolution & (resolution - 1)) != 0)
		throw std::invalid_argument(
			"texture_resolution = " + std::to_string(resolution) +
			" must be a power of two in [64, 4096]");
}

bool TextureOptions::operator==(const TextureOptions& o) const
{
	return style == o.style && seed == o.seed && base[0] == o.base[0] && base[1] == o.base[1] &&
		   base[2] == o.base[2] && sizeMetres == o.sizeMetres && resolution == o.resolution;
}

namespace
{
/** A colour far from `avoid` in brightness, so shapes have strong edges against the base. */
cv::Scalar contrastingColour(Rng& rng, double baseLuma)
{
	const double target = baseLuma > 128 ? rng.uniform(0, 70) : rng.uniform(185, 255);
	// A saturated tint around the target brightness.
	cv::Scalar c;
	for (int k = 0; k < 3; k++) c[k] = std::clamp(target + rng.uniform(-60, 60), 0.0, 255.0);
	return c;
}

cv::Scalar anyColour(Rng& rng)
{
	return cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255));
}

/** Draws `draw(offset)` at the 9 tile-periodic positions so the tile wraps seamlessly. */
template <class F>
void drawWrapped(int n, const F& draw)
{
	for (int dy = -1; dy <= 1; dy++)
		for (int dx = -1; dx <= 1; dx++) draw(cv::Point(dx * n, dy * n));
}

void drawRect(cv::Mat& img, Rng& rng, double pxPerM, double minM, double maxM, const cv::Scalar& c)
{
	const int n = img.cols;
	const cv::Point p(rng.below(n), rng.below(n));
	const int w = std::max(2, static_cast<int>(rng.uniform(minM, maxM) * pxPerM));
	const int h = std::max(2, static_cast<int>(rng.uniform(minM, maxM) * pxPerM));
	drawWrapped(n, [&](cv::Point o) {
		cv::rectangle(img, cv::Rect(p + o, cv::Size(w, h)), c, cv::FILLED, cv::LINE_8);
	});
}

void drawDisc(cv::Mat& img, Rng& rng, double pxPerM, double minM, double maxM, const cv::Scalar& c)
{
	const int n = img.cols;
	const cv::Point p(rng.below(n), rng.below(n));
	const int r = std::max(2, static_cast<int>(rng.uniform(minM, maxM) * pxPerM));
	drawWrapped(n, [&](cv::Point o) { cv::circle(img, p + o, r, c, cv::FILLED, cv::LINE_AA); });
}

void drawChecker(cv::Mat& img, Rng& rng, double pxPerM, const cv::Scalar& a, const cv::Scalar& b)
{
	const int n = img.cols;
	const cv::Point p(rng.below(n), rng.below(n));
	const int cell = std::max(3, static_cast<int>(rng.uniform(0.015, 0.04) * pxPerM));
	const int cells = 3 + rng.below(4);
	drawWrapped(n, [&](cv::Point o) {
		for (int i = 0; i < cells; i++)
			for (int j = 0; j < cells; j++)
				cv::rectangle(
					img, cv::Rect(p + o + cv::Point(i * cell, j * cell), cv::Size(cell, cell)),
					((i + j) % 2) ? a : b, cv::FILLED, cv::LINE_8);
	});
}

cv::Mat generate(const TextureOptions& o)
{
	const int n = o.resolution;
	const double pxPerM = n / o.sizeMetres;
	const double area = o.sizeMetres * o.sizeMetres;  // [m^2] shape counts scale with it
	const cv::Scalar base(o.base[0], o.base[1], o.base[2]);
	cv::Mat img(n, n, CV_8UC3, base);
	if (o.style == "plain") return img;
	Rng rng(mix64(o.seed) ^ hashString(o.style.c_str()));
	const double luma = 0.114 * o.base[0] + 0.587 * o.base[1] + 0.299 * o.base[2];

	// Low-frequency mottling: large soft patches of a shifted base tone (blob-like at coarse
	// scale).
	for (int i = 0, cnt = static_cast<int>(6 * area); i < cnt; i++)
	{
		cv::Scalar c = base;
		const double shift = rng.uniform(-45, 45);
		for (int k = 0; k < 3; k++) c[k] = std::clamp(c[k] + shift, 0.0, 255.0);
		drawDisc(img, rng, pxPerM, 0.08, 0.25, c);
	}
	const bool rects = o.style == "mixed" || o.style == "checker";
	const bool discs = o.style == "mixed" || o.style == "blobs";
	const bool checkers = o.style == "mixed" || o.style == "checker";
	const int nRect = rects ? static_cast<int>((o.style == "checker" ? 40 : 70) * area) : 0;
	const int nDisc = discs ? static_cast<int>((o.style == "blobs" ? 110 : 60) * area) : 0;
	const int nCheck = checkers ? static_cast<int>((o.style == "checker" ? 30 : 8) * area) : 0;
	// Interleave the shapes so that later ones partly cover earlier ones: T- and L-junctions
	// are the corners feature detectors like.
	const int total = nRect + nDisc + nCheck;
	for (int i = 0; i < total; i++)
	{
		const int kind = rng.below(total);
		const cv::Scalar c = rng.uniform() < 0.7 ? contrastingColour(rng, luma) : anyColour(rng);
		if (kind < nRect)
			drawRect(img, rng, pxPerM, 0.02, 0.12, c);
		else if (kind < nRect + nDisc)
			drawDisc(img, rng, pxPerM, 0.01, 0.06, c);
		else
			drawChecker(img, rng, pxPerM, c, contrastingColour(rng, 255 - luma));
	}
	return img;
}
}  // namespace

Texture::Texture(const TextureOptions& opts) : m_opts(opts)
{
	m_opts.validate();
	m_levels.push_back(generate(m_opts));
	// Mip levels down to 64 px: each halves the resolution (Gaussian pyramid).
	while (m_levels.back().cols > 64)
	{
		cv::Mat next;
		cv::pyrDown(m_levels.back(), next);
		m_levels.push_back(next);
	}
	m_texelMetres = m_opts.sizeMetres / m_opts.resolution;
}

void Texture::sample(double u, double v, double footprint, float bgr[3]) const
{
	// Mip level: the finest whose texel is at least half the pixel footprint.
	std::size_t lvl = 0;
	double texel = m_texelMetres;
	while (lvl + 1 < m_levels.size() && texel * 2.0 < footprint)
	{
		texel *= 2.0;
		lvl++;
	}
	const cv::Mat& img = m_levels[lvl];
	const int n = img.cols;  // power of two: wrapping is a mask
	const int mask = n - 1;
	// Texel centres at (i + 0.5) * texel.
	const double x = u / texel - 0.5, y = v / texel - 0.5;
	const double fx = std::floor(x), fy = std::floor(y);
	const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
	// floor() of huge coordinates is still exact for any scene size used here (< 2^31 texels).
	const int x0 = static_cast<int>(static_cast<long long>(fx) & mask);
	const int y0 = static_cast<int>(static_cast<long long>(fy) & mask);
	const int x1 = (x0 + 1) & mask, y1 = (y0 + 1) & mask;
	const auto* r0 = img.ptr<cv::Vec3b>(y0);
	const auto* r1 = img.ptr<cv::Vec3b>(y1);
	for (int k = 0; k < 3; k++)
	{
		const float top = r0[x0][k] + ax * (r0[x1][k] - r0[x0][k]);
		const float bot = r1[x0][k] + ax * (r1[x1][k] - r1[x0][k]);
		bgr[k] = top + ay * (bot - top);
	}
}

}  // namespace keygrid::sim

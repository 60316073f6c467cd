#include <keygrid/core/CommandLine.h>
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/ProgressBar.h>
#include <keygrid/loop/Vocabulary.h>
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/VocabApp.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

namespace keygrid::slam
{
namespace
{
namespace fs = std::filesystem;

/** Image paths of a folder (sorted) or of a list file (one path per line, '#' comments,
 * relative paths resolved against the list's folder). */
std::vector<std::string> imagePaths(const std::string& where)
{
	std::vector<std::string> out;
	if (fs::is_directory(where))
	{
		static const std::vector<std::string> exts{".png", ".jpg", ".jpeg", ".bmp", ".ppm", ".pgm", ".tif", ".tiff"};
		for (const auto& e : fs::directory_iterator(where))
		{
			std::string ext = e.path().extension().string();
			std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
			if (e.is_regular_file() && std::find(exts.begin(), exts.end(), ext) != exts.end()) out.push_back(e.path().string());
		}
		std::sort(out.begin(), out.end());
		if (out.empty()) throw std::runtime_error("no images (png, jpg, bmp, ppm, pgm, tif) in " + where);
		return out;
	}
	std::ifstream f(where);
	if (!f) throw std::runtime_error("cannot open image folder or list " + where);
	const fs::path base = fs::path(where).parent_path();
	std::string line;
	while (std::getline(f, line))
	{
		line.erase(0, line.find_first_not_of(" \t\r"));
		line.erase(line.find_last_not_of(" \t\r") + 1);
		if (line.empty() || line[0] == '#') continue;
		const fs::path p(line);
		out.push_back(p.is_absolute() ? p.string() : (base / p).string());
	}
	if (out.empty()) throw std::runtime_error("image list " + where + " names no images");
	return out;
}

class DescriptorExtractor
{
   public:
	DescriptorExtractor(const std::string& kind, int features)
	{
		if (kind == "orb") m_f = cv::ORB::create(features);
		else if (kind == "sift") m_f = cv::SIFT::create(features);
		else throw core::CommandLineError("--features " + kind + " (must be orb or sift)");
	}
	cv::Mat operator()(const cv::Mat& image) const
	{
		cv::Mat grey = image;
		if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
		std::vector<cv::KeyPoint> kps;
		cv::Mat d;
		m_f->detectAndCompute(grey, cv::noArray(), kps, d);
		return d;
	}

   private:
	cv::Ptr<cv::Feature2D> m_f;
};

/** Training options of the command line (--k, --levels, --seed, --threads), checked by the
 * rules of VocabularyOptions' INI keys; an error names the option as typed. */
loop::VocabularyOptions vocabularyOptions(const core::CommandLine& cl)
{
	// The command-line option of each INI key the command line sets.
	const std::map<std::string, std::string> optionOfKey{{"branching", "k"}, {"levels", "levels"}, {"seed", "seed"}, {"threads", "threads"}};
	loop::VocabularyOptions vo;
	vo.branching = static_cast<int>(cl.getInt("k"));
	vo.levels = static_cast<int>(cl.getInt("levels"));
	vo.seed = static_cast<std::uint64_t>(cl.getInt("seed"));
	vo.threads = static_cast<int>(cl.getInt("threads"));
	const core::OptionFields table = vo.fields();
	for (const auto& f : table.fields())
		if (const auto o = optionOfKey.find(f.key); o != optionOfKey.end() && !f.accepted())
			throw core::CommandLineError("--" + o->second + " " + cl.get(o->second) + " (must be " + f.rule.text() + ")");
	try
	{
		vo.validate("vocabulary");
	}
	catch (const std::invalid_argument& e)
	{
		throw core::CommandLineError(std::string("--k, --levels: ") + e.what());
	}
	return vo;
}

/** The descriptors of the training images, one matrix per image, with their count. */
class TrainingDescriptors
{
   public:
	/** --max-images (0: all) and --every of the command line. */
	TrainingDescriptors(long maxImages, long every) : m_maxImages(maxImages), m_every(every) {}

	/** Whether the image of this index (0, 1, ... in input order) is one to use. */
	bool keep(std::size_t index) const { return index % static_cast<std::size_t>(m_every) == 0; }
	/** Whether --max-images images are collected. */
	bool full() const { return m_maxImages > 0 && m_perImage.size() >= static_cast<std::size_t>(m_maxImages); }
	void add(const cv::Mat& d)
	{
		m_perImage.push_back(d);
		m_total += static_cast<std::size_t>(d.rows);
	}
	const std::vector<cv::Mat>& perImage() const { return m_perImage; }
	std::size_t total() const { return m_total; }

   private:
	long m_maxImages, m_every;
	std::vector<cv::Mat> m_perImage;
	std::size_t m_total{0};
};

/** --images: the descriptors of a folder of images or of an image list. */
void collectFromImages(const std::string& where, const DescriptorExtractor& extract, TrainingDescriptors& descriptors)
{
	const auto paths = imagePaths(where);
	core::ProgressBar bar("extracting", paths.size());
	for (std::size_t i = 0; i < paths.size() && !descriptors.full(); ++i)
	{
		if (!descriptors.keep(i)) continue;
		const cv::Mat img = cv::imread(paths[i], cv::IMREAD_GRAYSCALE);
		if (img.empty()) throw std::runtime_error("cannot read image " + paths[i]);
		descriptors.add(extract(img));
		bar.update(i + 1, std::to_string(descriptors.total()) + " descriptors");
	}
	bar.finish(std::to_string(descriptors.total()) + " descriptors");
}

/** --rawlog / --tum: the descriptors of the grey images of a recorded sequence. */
void collectFromSequence(const core::CommandLine& cl, const DescriptorExtractor& extract, TrainingDescriptors& descriptors)
{
	const std::string path = cl.has("rawlog") ? cl.get("rawlog") : cl.get("tum");
	if (cl.has("tum") && !fs::is_directory(path)) throw std::runtime_error("--tum " + path + " is not a folder");
	if (cl.has("rawlog") && !fs::is_regular_file(path)) throw std::runtime_error("--rawlog " + path + " is not a file");
	auto src = core::openFrameSource(path);
	core::ProgressBar bar("extracting", src->sizeHint().value_or(0));
	core::Frame f;
	std::size_t index = 0;
	while (!descriptors.full() && src->next(f))
	{
		if (descriptors.keep(index++) && !f.grey.empty()) descriptors.add(extract(f.grey));
		bar.update(index, std::to_string(descriptors.total()) + " descriptors");
	}
	bar.finish(std::to_string(descriptors.total()) + " descriptors");
}

/** Number of images with features; throws unless there are at least 2: idf = log(images /
 * images with the word), so with one image every word has weight 0 and every place would
 * score alike. */
long imagesWithFeatures(const TrainingDescriptors& descriptors)
{
	if (descriptors.total() == 0) throw std::runtime_error("no descriptors extracted (no images or no texture)");
	const auto& d = descriptors.perImage();
	const auto withFeatures = std::count_if(d.begin(), d.end(), [](const cv::Mat& m) { return m.rows > 0; });
	if (withFeatures < 2)
		throw std::runtime_error(
			"training needs at least 2 images with features, got " + std::to_string(withFeatures) +
			" (with one, every word is in every image and weighs 0)");
	return static_cast<long>(withFeatures);
}

int train(const core::CommandLine& cl)
{
	const int inputs = cl.has("images") + cl.has("rawlog") + cl.has("tum");
	if (inputs != 1) throw core::CommandLineError("train needs exactly one of --images, --rawlog, --tum");
	if (!cl.has("output")) throw core::CommandLineError("missing --output");
	const loop::VocabularyOptions vo = vocabularyOptions(cl);
	const long maxImages = cl.getInt("max-images");
	const long every = cl.getInt("every");
	const long features = cl.getInt("nfeatures");
	if (maxImages < 0) throw core::CommandLineError("--max-images " + cl.get("max-images") + " (must be >= 0)");
	if (every < 1) throw core::CommandLineError("--every " + cl.get("every") + " (must be >= 1)");
	if (features < 1) throw core::CommandLineError("--nfeatures " + cl.get("nfeatures") + " (must be >= 1)");
	const DescriptorExtractor extract(cl.get("features"), static_cast<int>(features));

	TrainingDescriptors descriptors(maxImages, every);
	if (cl.has("images"))
		collectFromImages(cl.get("images"), extract, descriptors);
	else
		collectFromSequence(cl, extract, descriptors);
	const long withFeatures = imagesWithFeatures(descriptors);

	core::ProgressBar bar("clustering", descriptors.total());
	const loop::Vocabulary v = loop::Vocabulary::train(descriptors.perImage(), vo, [&](std::size_t done, std::size_t) { bar.update(done); });
	bar.finish();
	bool anyWeight = false;
	for (std::size_t w = 0; w < v.numWords() && !anyWeight; ++w) anyWeight = v.idf(static_cast<loop::WordId>(w)) > 0;
	if (!anyWeight)
		throw std::runtime_error(
			"every word of the vocabulary is in every one of the " + std::to_string(withFeatures) +
			" training images, so every word weighs 0: train on more, and more varied, images");
	std::ostringstream os;
	v.save(os);
	core::writeFileAtomically(cl.get("output"), os.str());
	std::cout << v.describe() << "\n"
			  << "trained on " << descriptors.total() << " descriptors in " << std::fixed << std::setprecision(1) << bar.elapsed()
			  << " s -> " << cl.get("output") << " (" << os.str().size() / 1024 << " KiB)\n";
	return 0;
}

int info(const std::string& path)
{
	const loop::Vocabulary v = loop::Vocabulary::load(path);
	std::size_t zeroIdf = 0;
	double sumIdf = 0, maxIdf = 0;
	for (std::size_t w = 0; w < v.numWords(); ++w)
	{
		const double idf = v.idf(static_cast<loop::WordId>(w));
		sumIdf += idf;
		maxIdf = std::max(maxIdf, idf);
		zeroIdf += idf <= 0;
	}
	std::cout << path << ": " << v.describe() << "\n"
			  << "idf: mean " << sumIdf / static_cast<double>(v.numWords()) << ", max " << maxIdf << ", " << zeroIdf
			  << " words in every training image (ignored)\n";
	return 0;
}
}  // namespace

int VocabApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-vocab", [&] {
		core::CommandLine cl(
			"keygrid-vocab",
			"Vocabulary trees for loop closure (Nister & Stewenius hierarchical k-means, TF-IDF).\n"
			"  keygrid-vocab train (--images DIR|LIST | --rawlog X.rawlog | --tum TUM_DIR) --output vocab.bin\n"
			"  keygrid-vocab info vocab.bin\n"
			"Training needs nothing downloaded: use the sequence to be mapped itself (a pre-pass) or\n"
			"any images of similar scenes.");
		cl.positionals("train | info VOCAB", "sub-command (and the vocabulary file for info)")
			.option("images", "DIR|LIST", "train on a folder of images or a text file listing image paths")
			.option("rawlog", "X.rawlog", "train on the grey images of an MRPT rawlog")
			.option("tum", "TUM_DIR", "train on the rgb images of a TUM RGB-D folder")
			.option("output", "vocab.bin", "vocabulary file to write (train)")
			.option("k", "K", "branching factor", false, "10")
			.option("levels", "L", "tree depth (at most K^L words)", false, "4")
			.option("features", "orb|sift", "descriptor: ORB (binary, Hamming) or SIFT (float, L2)", false, "orb")
			.option("nfeatures", "N", "features per image", false, "1000")
			.option("max-images", "N", "use at most N images (0: all)", false, "0")
			.option("every", "N", "use every N-th image/frame", false, "1")
			.option("seed", "S", "k-means++ seed (same seed, same vocabulary)", false, "1")
			.option("threads", "T", "training threads (0: all cores)", false, "0");
		if (!cl.parse(argc, argv)) return 0;
		const auto& pos = cl.positional();
		if (pos.empty()) throw core::CommandLineError("missing sub-command (train or info)");
		if (pos[0] == "train")
		{
			if (pos.size() != 1) throw core::CommandLineError("unexpected argument '" + pos[1] + "'");
			return train(cl);
		}
		if (pos[0] == "info")
		{
			if (pos.size() != 2) throw core::CommandLineError("info needs exactly one vocabulary file");
			return info(pos[1]);
		}
		throw core::CommandLineError("unknown sub-command '" + pos[0] + "' (train or info)");
	});
}

}  // namespace keygrid::slam

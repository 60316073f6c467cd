#include <keygrid/core/TimestampAssociation.h>
#include <keygrid/core/TumSequence.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace keygrid::core
{
namespace
{
std::vector<TumStampedFile> readStampedList(
	const std::string& path, std::vector<TextLineIssue>& issues)
{
	std::vector<TumStampedFile> out;
	for (const auto& rec : readTumTextRecords(path))
	{
		double t = 0;
		if (rec.fields.size() != 2 || !parseDouble(rec.fields[0], t))
		{
			issues.push_back({path, rec.line, "expected 'timestamp filename'"});
			continue;
		}
		out.push_back({t, rec.fields[1]});
	}
	return out;
}

std::string lower(std::string s)
{
	for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
	return s;
}
}  // namespace

TumSequence::TumSequence(const std::string& dirIn, double maxDt, DepthUse depth)
	: m_dir(dirIn), m_hasDepth(depth == DepthUse::Use)
{
	while (m_dir.size() > 1 && m_dir.back() == '/') m_dir.pop_back();
	if (!mrpt::system::directoryExists(m_dir))
		throw std::runtime_error("TUM folder '" + m_dir + "' does not exist");
	const bool haveAssoc = mrpt::system::fileExists(m_dir + "/associations.txt");
	const bool haveRgb = mrpt::system::fileExists(m_dir + "/rgb.txt");
	if (depth == DepthUse::Ignore)
	{
		// Every colour image of rgb.txt, paired with depth or not; associations.txt's colour
		// column when a folder lists its images only there.
		if (haveRgb)
			indexImages();
		else if (haveAssoc)
			indexAssociations(DepthUse::Ignore);
		else
			throw std::runtime_error("TUM folder '" + m_dir + "' has neither rgb.txt nor associations.txt");
	}
	else if (haveAssoc)
		indexAssociations(DepthUse::Use);
	else
		indexLists(maxDt);
	if (m_pairs.empty())
		throw std::runtime_error(
			"TUM folder '" + m_dir + "': " + m_indexSource + " gives no " +
			(depth == DepthUse::Use ? "rgb/depth pair" : "colour image") +
			(m_issues.empty() ? std::string() : " (" + m_issues.front().str() + ")"));
}

std::string TumSequence::absolute(const std::string& f) const
{
	return f.empty() || f[0] == '/' ? f : m_dir + "/" + f;
}

void TumSequence::indexAssociations(DepthUse depth)
{
	const std::string assoc = m_dir + "/associations.txt";
	m_indexSource = "associations.txt";
	for (const auto& rec : readTumTextRecords(assoc))
	{
		double t1 = 0, t2 = 0;
		if (rec.fields.size() < 4 || !parseDouble(rec.fields[0], t1) || !parseDouble(rec.fields[2], t2))
		{
			m_issues.push_back({assoc, rec.line, "expected 't1 file1 t2 file2'"});
			continue;
		}
		TumPair p{t1, t2, absolute(rec.fields[1]), absolute(rec.fields[3])};
		// associate.py writes the lists in the order it was given: accept depth first.
		if (lower(rec.fields[1]).find("depth") != std::string::npos &&
			lower(rec.fields[3]).find("depth") == std::string::npos)
		{
			std::swap(p.tRgb, p.tDepth);
			std::swap(p.rgbPath, p.depthPath);
		}
		if (depth == DepthUse::Ignore) p = {p.tRgb, 0, p.rgbPath, {}};
		m_pairs.push_back(p);
	}
}

void TumSequence::indexLists(double maxDt)
{
	m_indexSource = "rgb.txt+depth.txt";
	for (const char* f : {"/rgb.txt", "/depth.txt"})
		if (!mrpt::system::fileExists(m_dir + f))
			throw std::runtime_error(
				"TUM folder '" + m_dir + "' has neither associations.txt nor " + (f + 1) +
				(std::string(f) == "/depth.txt" ? " (without depth it is an image-only input: read it with depth ignored)"
												: ""));
	const auto rgb = readStampedList(m_dir + "/rgb.txt", m_issues);
	const auto depth = readStampedList(m_dir + "/depth.txt", m_issues);
	std::vector<double> tr, td;
	for (const auto& e : rgb) tr.push_back(e.t);
	for (const auto& e : depth) td.push_back(e.t);
	for (const auto& [i, j] : associateTimestamps(tr, td, maxDt))
		m_pairs.push_back({rgb[i].t, depth[j].t, absolute(rgb[i].file), absolute(depth[j].file)});
}

void TumSequence::indexImages()
{
	m_indexSource = "rgb.txt";
	for (const auto& e : readStampedList(m_dir + "/rgb.txt", m_issues)) m_pairs.push_back({e.t, 0, absolute(e.file), {}});
}

RgbdCamera TumSequence::guessCamera() const
{
	const std::string ini = m_dir + "/camera.ini";
	if (mrpt::system::fileExists(ini)) return RgbdCamera::FromPresetOrFile(ini);
	const std::string name = lower(mrpt::system::extractFileName(m_dir) + "/" + m_dir);
	const std::string base = lower(mrpt::system::extractFileName(m_dir));
	for (const std::string& s : {base, name})
	{
		if (s.find("fr1") != std::string::npos || s.find("freiburg1") != std::string::npos)
			return RgbdCamera::Preset("fr1");
		if (s.find("fr2") != std::string::npos || s.find("freiburg2") != std::string::npos)
			return RgbdCamera::Preset("fr2");
		if (s.find("fr3") != std::string::npos || s.find("freiburg3") != std::string::npos)
			return RgbdCamera::Preset("fr3");
		if (s.find("icl") != std::string::npos) return RgbdCamera::Preset("icl");
	}
	return RgbdCamera::Preset("kinect");
}

}  // namespace keygrid::core

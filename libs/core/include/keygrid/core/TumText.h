#pragma once
/** \file TumText.h
 * Line parsing shared by TUM RGB-D text files (rgb.txt, depth.txt, associations.txt,
 * groundtruth.txt and trajectories): '#' comments, blank lines, whitespace or comma separators.
 */
#include <string>
#include <vector>

namespace keygrid::core
{
/** A problem found on one line of a text file. */
struct TextLineIssue
{
	std::string file;
	std::size_t line{0};  //!< 1-based
	std::string reason;
	std::string str() const { return file + ":" + std::to_string(line) + ": " + reason; }
};

/** One non-comment line split into fields, with its 1-based line number. */
struct TextRecord
{
	std::size_t line{0};
	std::vector<std::string> fields;
};

/** Reads `path` into records (comments and blank lines dropped). Throws std::runtime_error
 * when the file cannot be opened. */
std::vector<TextRecord> readTumTextRecords(const std::string& path);

/** Parses a whole field as a finite double. Returns false on garbage, partial numbers or inf/nan. */
bool parseDouble(const std::string& field, double& out);

}  // namespace keygrid::core

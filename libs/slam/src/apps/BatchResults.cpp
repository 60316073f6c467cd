/** \file BatchResults.cpp
 * report.json reading and the results tables of keygrid-batch.
 */
#include <keygrid/slam/apps/BatchResults.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
using Json = nlohmann::json;

std::optional<double> numberOf(const Json& obj, const char* key)
{
	const auto it = obj.find(key);
	if (it == obj.end() || !it->is_number()) return std::nullopt;
	return it->get<double>();
}

std::string fmt(const std::optional<double>& v, const char* f)
{
	if (!v) return "";
	char b[64];
	std::snprintf(b, sizeof(b), f, *v);
	return b;
}

std::string csvField(const std::string& s)
{
	if (s.find_first_of(",\"\n") == std::string::npos) return s;
	std::string o = "\"";
	for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
	return o + "\"";
}

std::string mdCell(const std::string& s)
{
	std::string o;
	for (char c : s)
	{
		if (c == '|') o += '\\';
		o += c == '\n' ? ' ' : c;
	}
	return o;
}
}  // namespace

RunMetrics readRunReport(const std::string& reportPath)
{
	if (!mrpt::system::fileExists(reportPath)) throw std::runtime_error("no " + reportPath);
	Json doc;
	try
	{
		doc = Json::parse(mrpt::io::file_get_contents(reportPath));
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(reportPath + ": " + e.what());
	}
	if (!doc.is_object()) throw std::runtime_error(reportPath + ": not a JSON object");
	RunMetrics m;
	m.frames = numberOf(doc, "frames");
	m.tracked = numberOf(doc, "tracked");
	m.fps = numberOf(doc, "fps");
	m.ateRmse = numberOf(doc, "ate_rmse_m");
	m.keyframes = numberOf(doc, "keyframes");
	m.landmarks = numberOf(doc, "landmarks");
	if (const auto it = doc.find("loop_closures"); it != doc.end() && it->is_array()) m.loopClosures = static_cast<double>(it->size());
	if (const auto it = doc.find("error"); it != doc.end() && it->is_string())
	{
		const auto text = it->get<std::string>();
		m.error = text.empty() ? "error (no message)" : text;
	}
	return m;
}

std::optional<double> medianOf(const std::vector<std::optional<double>>& values)
{
	std::vector<double> v;
	for (const auto& x : values)
		if (x) v.push_back(*x);
	if (v.empty()) return std::nullopt;
	std::sort(v.begin(), v.end());
	const std::size_t n = v.size();
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<ResultRow> aggregateRuns(const std::vector<RunMetrics>& runs)
{
	std::vector<ResultRow> rows;
	std::vector<std::vector<const RunMetrics*>> members;
	for (const auto& r : runs)
	{
		std::size_t i = 0;
		while (i < rows.size() && !(rows[i].dataset == r.dataset && rows[i].config == r.config)) i++;
		if (i == rows.size())
		{
			rows.push_back({});
			rows.back().dataset = r.dataset;
			rows.back().config = r.config;
			members.emplace_back();
		}
		members[i].push_back(&r);
	}
	for (std::size_t i = 0; i < rows.size(); i++)
	{
		ResultRow& row = rows[i];
		row.runs = static_cast<int>(members[i].size());
		std::vector<const RunMetrics*> use;
		for (const RunMetrics* r : members[i])
		{
			if (r->ok())
				use.push_back(r);
			else if (row.failed++ == 0)
				row.error = r->error;
		}
		if (row.failed > 0 && row.runs > 1)
			row.error = std::to_string(row.failed) + " of " + std::to_string(row.runs) + " runs failed: " + row.error;
		if (use.empty()) use = members[i];  // show how far the failed runs got
		auto med = [&](std::optional<double> RunMetrics::*field) {
			std::vector<std::optional<double>> v;
			for (const RunMetrics* r : use) v.push_back(r->*field);
			return medianOf(v);
		};
		row.frames = med(&RunMetrics::frames);
		row.tracked = med(&RunMetrics::tracked);
		row.fps = med(&RunMetrics::fps);
		row.ateRmse = med(&RunMetrics::ateRmse);
		row.keyframes = med(&RunMetrics::keyframes);
		row.landmarks = med(&RunMetrics::landmarks);
		row.loopClosures = med(&RunMetrics::loopClosures);
	}
	return rows;
}

std::string resultsMarkdown(const std::vector<ResultRow>& rows)
{
	std::string s =
		"| dataset | config | runs ok | frames | tracked | fps | ATE RMSE [cm] | keyframes | landmarks | loop closures | error |\n"
		"|---|---|---|---|---|---|---|---|---|---|---|\n";
	for (const auto& r : rows)
	{
		const std::optional<double> ateCm = r.ateRmse ? std::optional<double>(100.0 * *r.ateRmse) : std::nullopt;
		s += "| " + mdCell(r.dataset) + " | " + mdCell(r.config) + " | " + std::to_string(r.runs - r.failed) + "/" +
			 std::to_string(r.runs) + " | " + fmt(r.frames, "%g") + " | " + fmt(r.tracked, "%g") + " | " +
			 fmt(r.fps, "%.1f") + " | " + fmt(ateCm, "%.2f") + " | " + fmt(r.keyframes, "%g") + " | " +
			 fmt(r.landmarks, "%g") + " | " + fmt(r.loopClosures, "%g") + " | " + mdCell(r.error) + " |\n";
	}
	return s;
}

std::string resultsCsv(const std::vector<ResultRow>& rows)
{
	std::string s = "dataset,config,runs,failed,frames,tracked,fps,ate_rmse_m,keyframes,landmarks,loop_closures,error\n";
	for (const auto& r : rows)
		s += csvField(r.dataset) + "," + csvField(r.config) + "," + std::to_string(r.runs) + "," + std::to_string(r.failed) +
			 "," + fmt(r.frames, "%g") + "," + fmt(r.tracked, "%g") + "," + fmt(r.fps, "%.3f") + "," +
			 fmt(r.ateRmse, "%.9g") + "," + fmt(r.keyframes, "%g") + "," + fmt(r.landmarks, "%g") + "," +
			 fmt(r.loopClosures, "%g") + "," + csvField(r.error) + "\n";
	return s;
}

std::string runsCsv(const std::vector<RunMetrics>& runs)
{
	std::string s = "dataset,config,repeat,seconds,frames,tracked,fps,ate_rmse_m,keyframes,landmarks,loop_closures,error,run_dir\n";
	for (const auto& r : runs)
		s += csvField(r.dataset) + "," + csvField(r.config) + "," + std::to_string(r.repeat) + "," +
			 fmt(r.seconds, "%.2f") + "," + fmt(r.frames, "%g") + "," + fmt(r.tracked, "%g") + "," + fmt(r.fps, "%.3f") +
			 "," + fmt(r.ateRmse, "%.9g") + "," + fmt(r.keyframes, "%g") + "," + fmt(r.landmarks, "%g") + "," +
			 fmt(r.loopClosures, "%g") + "," + csvField(r.error) + "," + csvField(r.runDir) + "\n";
	return s;
}

}  // namespace keygrid::slam

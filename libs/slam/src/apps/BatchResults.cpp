/** \file BatchResults.cpp
 * report.json reading (a small strict JSON reader: keygrid has no JSON dependency) and the
 * results tables of keygrid-batch.
 */
#include <keygrid/slam/apps/BatchResults.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>

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
/** A JSON value; only what report.json needs is kept (numbers, strings, array lengths). */
struct JsonValue
{
	enum class Type
	{
		Null,
		Bool,
		Number,
		String,
		Array,
		Object
	} type{Type::Null};
	double number{0};
	std::string text;
	std::size_t arraySize{0};
	std::map<std::string, JsonValue> members;
};

class JsonReader
{
   public:
	explicit JsonReader(const std::string& s) : m_s(s) {}

	JsonValue document()
	{
		JsonValue v = value();
		blanks();
		if (m_i != m_s.size()) fail("trailing characters");
		return v;
	}

   private:
	const std::string& m_s;
	std::size_t m_i{0};

	[[noreturn]] void fail(const std::string& why) const
	{
		throw std::runtime_error("invalid JSON at offset " + std::to_string(m_i) + ": " + why);
	}
	void blanks()
	{
		while (m_i < m_s.size() && (m_s[m_i] == ' ' || m_s[m_i] == '\n' || m_s[m_i] == '\t' || m_s[m_i] == '\r')) m_i++;
	}
	bool take(char c)
	{
		blanks();
		if (m_i < m_s.size() && m_s[m_i] == c)
		{
			m_i++;
			return true;
		}
		return false;
	}
	void expect(char c)
	{
		if (!take(c)) fail(std::string("expected '") + c + "'");
	}
	bool word(const char* w)
	{
		const std::size_t n = std::char_traits<char>::length(w);
		if (m_s.compare(m_i, n, w) != 0) return false;
		m_i += n;
		return true;
	}
	std::string string()
	{
		expect('"');
		std::string o;
		while (m_i < m_s.size() && m_s[m_i] != '"')
		{
			char c = m_s[m_i++];
			if (c == '\\')
			{
				if (m_i >= m_s.size()) break;
				c = m_s[m_i++];
				switch (c)
				{
					case 'n': c = '\n'; break;
					case 't': c = '\t'; break;
					case 'r': c = '\r'; break;
					case 'b': c = '\b'; break;
					case 'f': c = '\f'; break;
					case 'u':
						// Non-ASCII escapes are not produced by keygrid; keep them as '?'.
						if (m_i + 4 > m_s.size()) fail("short \\u escape");
						m_i += 4;
						c = '?';
						break;
					default: break;  // '"', '\\', '/'
				}
			}
			o += c;
		}
		if (m_i >= m_s.size()) fail("unterminated string");
		m_i++;
		return o;
	}
	JsonValue value()
	{
		blanks();
		if (m_i >= m_s.size()) fail("unexpected end");
		JsonValue v;
		const char c = m_s[m_i];
		if (c == '{')
		{
			m_i++;
			v.type = JsonValue::Type::Object;
			if (take('}')) return v;
			do
			{
				blanks();
				const std::string k = string();
				expect(':');
				v.members[k] = value();
			} while (take(','));
			expect('}');
		}
		else if (c == '[')
		{
			m_i++;
			v.type = JsonValue::Type::Array;
			if (take(']')) return v;
			do
			{
				value();
				v.arraySize++;
			} while (take(','));
			expect(']');
		}
		else if (c == '"')
		{
			v.type = JsonValue::Type::String;
			v.text = string();
		}
		else if (word("null"))
			v.type = JsonValue::Type::Null;
		else if (word("true"))
		{
			v.type = JsonValue::Type::Bool;
			v.number = 1;
		}
		else if (word("false"))
			v.type = JsonValue::Type::Bool;
		else
		{
			const char* begin = m_s.c_str() + m_i;
			char* end = nullptr;
			v.number = std::strtod(begin, &end);
			if (end == begin) fail("unexpected character");
			v.type = JsonValue::Type::Number;
			m_i += static_cast<std::size_t>(end - begin);
		}
		return v;
	}
};

std::optional<double> numberOf(const JsonValue& obj, const std::string& key)
{
	const auto it = obj.members.find(key);
	if (it == obj.members.end() || it->second.type != JsonValue::Type::Number) return std::nullopt;
	return it->second.number;
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
	JsonValue doc;
	try
	{
		doc = JsonReader(mrpt::io::file_get_contents(reportPath)).document();
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(reportPath + ": " + e.what());
	}
	if (doc.type != JsonValue::Type::Object) throw std::runtime_error(reportPath + ": not a JSON object");
	RunMetrics m;
	m.frames = numberOf(doc, "frames");
	m.tracked = numberOf(doc, "tracked");
	m.fps = numberOf(doc, "fps");
	m.ateRmse = numberOf(doc, "ate_rmse_m");
	m.keyframes = numberOf(doc, "keyframes");
	m.landmarks = numberOf(doc, "landmarks");
	if (const auto it = doc.members.find("loop_closures"); it != doc.members.end() && it->second.type == JsonValue::Type::Array)
		m.loopClosures = static_cast<double>(it->second.arraySize);
	if (const auto it = doc.members.find("error"); it != doc.members.end() && it->second.type == JsonValue::Type::String)
		m.error = it->second.text.empty() ? "error (no message)" : it->second.text;
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

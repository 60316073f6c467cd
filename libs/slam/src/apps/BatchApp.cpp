/** \file BatchApp.cpp
 * keygrid-batch: prepares the configuration copies, generates the synthetic datasets with
 * keygrid-sim, runs keygrid-slam on every (dataset, config, repeat) as child processes and
 * writes the results tables (see BatchApp.h).
 */
#include <keygrid/core/CommandLine.h>
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/BatchApp.h>
#include <keygrid/slam/apps/BatchProcess.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <thread>

namespace keygrid::slam
{
namespace
{
namespace fs = std::filesystem;

std::string selfDir()
{
	std::error_code ec;
	const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
	return ec ? std::string(".") : exe.parent_path().string();
}

std::string readText(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream ss;
	ss << f.rdbuf();
	return ss.str();
}

/** The reason a tool printed ("<tool>: error: <reason>"), else its last non-empty line. */
std::string reasonFromLog(const std::string& logPath)
{
	std::istringstream in(readText(logPath));
	std::string lastError, last;
	for (std::string l; std::getline(in, l);)
	{
		if (!l.empty() && l.back() == '\r') l.pop_back();
		if (l.find_first_not_of(" \t") == std::string::npos) continue;
		// Progress bars redraw with '\r': keep the text after the last one.
		if (const auto cr = l.rfind('\r'); cr != std::string::npos) l = l.substr(cr + 1);
		last = l;
		if (const auto e = l.find("error: "); e != std::string::npos) lastError = l.substr(e + 7);
	}
	return lastError.empty() ? last : lastError;
}

std::string utcNow()
{
	const std::time_t t = std::time(nullptr);
	std::tm tm{};
	gmtime_r(&t, &tm);
	char b[64];
	std::strftime(b, sizeof(b), "%Y-%m-%d %H:%M UTC", &tm);
	return b;
}

/** "AMD EPYC 7B13 (2 cores), 24 GB, Debian GNU/Linux 12 (bookworm)" */
std::string machineDescription()
{
	auto field = [](const std::string& file, const std::string& key) {
		std::istringstream in(readText(file));
		for (std::string l; std::getline(in, l);)
			if (l.rfind(key, 0) == 0)
			{
				std::string v = l.substr(l.find_first_of(":=", key.size()) + 1);
				v.erase(0, v.find_first_not_of(" \t\""));
				while (!v.empty() && (v.back() == '"' || v.back() == ' ')) v.pop_back();
				return v;
			}
		return std::string();
	};
	std::ostringstream o;
	const std::string cpu = field("/proc/cpuinfo", "model name");
	o << (cpu.empty() ? "unknown CPU" : cpu) << " (" << std::thread::hardware_concurrency() << " cores)";
	const std::string mem = field("/proc/meminfo", "MemTotal");
	if (!mem.empty()) o << ", " << static_cast<long>(std::stod(mem) / 1048576.0 + 0.5) << " GB";
	const std::string os = field("/etc/os-release", "PRETTY_NAME");
	if (!os.empty()) o << ", " << os;
	// Timings depend on what else runs: the 1-minute load average when the batch started.
	std::istringstream load(readText("/proc/loadavg"));
	double l1 = -1;
	if (load >> l1) o << ", load average " << l1 << " at the start";
	return o.str();
}

/** The configuration file with its overrides, checked: throws naming the config and the key. */
std::string preparedConfig(const ConfigSpec& c)
{
	const std::string where = "[config." + c.name + "]";
	const std::string text = mrpt::io::file_get_contents(c.file);
	std::string applied = text;
	if (!c.overrides.empty())
	{
		checkOverrideKeys(text, c.overrides, where + " set");
		applied = applyOverrides(text, c.overrides);
	}
	try
	{
		mrpt::config::CConfigFileMemory mem(applied);
		SlamConfig cfg;
		cfg.loadFromConfigFile(mem);
		MetricMaps maps(mem, cfg.maps);  // every map the INI asks for must exist
	}
	catch (const std::exception& e)
	{
		throw std::invalid_argument(where + " (" + c.file + (c.overrides.empty() ? "" : " with set") + "): " + e.what());
	}
	std::string header = "# keygrid-batch: " + c.file;
	for (const auto& o : c.overrides) header += (&o == &c.overrides.front() ? " with " : "; ") + o.section + "." + o.key + "=" + o.value;
	return header + "\n" + applied;
}

/** A dataset as the runs use it: their --input and --gt, or why it could not be generated. */
struct PreparedDataset
{
	std::string input, gt, error;
};

std::string fmtCentimetres(double metres)
{
	char b[32];
	std::snprintf(b, sizeof(b), "%.2f cm", 100.0 * metres);
	return b;
}

std::string fmtSeconds(double s)
{
	char b[32];
	std::snprintf(b, sizeof(b), "%.1f s", s);
	return b;
}

/** Writes the configuration copies to OUT/_configs (validated before anything runs, written
 * unless dryRun); returns their paths, one per config of the spec. */
std::vector<std::string> writeConfigCopies(const ExperimentSpec& spec, const fs::path& out, bool dryRun)
{
	std::vector<std::string> configPaths;
	for (const auto& c : spec.configs)
	{
		const std::string text = preparedConfig(c);
		configPaths.push_back((out / "_configs" / (c.name + ".ini")).string());
		if (!dryRun)
		{
			fs::create_directories(out / "_configs");
			core::writeFileAtomically(configPaths.back(), text);
		}
	}
	return configPaths;
}

/** The keygrid-sim processes that generate the synthetic datasets not generated yet. */
struct DatasetGeneration
{
	std::vector<ProcessJob> jobs;
	std::vector<std::size_t> datasetOf;  //!< jobs[j] generates spec.datasets[datasetOf[j]]
	std::vector<std::string> stamps;  //!< jobs[j]'s generated-by.txt: its command and scene hash
};

/** The keygrid-sim command that generates dataset `d` into `dir`. */
ProcessJob simJob(const DatasetSpec& d, const std::string& simExe, const fs::path& dir)
{
	ProcessJob job;
	job.argv = {simExe, "--scene", d.scene, "--output", dir.string(), "--quiet"};
	if (d.seed) job.argv.insert(job.argv.end(), {"--seed", std::to_string(*d.seed)});
	if (d.frames) job.argv.insert(job.argv.end(), {"--frames", std::to_string(*d.frames)});
	if (!d.simSet.empty()) job.argv.insert(job.argv.end(), {"--set", d.simSet});
	job.logPath = (dir / "keygrid-sim.log").string();
	return job;
}

/** Runs the generation jobs; a dataset that failed gets the reason as its error. */
void generateDatasets(const ExperimentSpec& spec, const fs::path& out, const DatasetGeneration& gen, std::vector<PreparedDataset>& data)
{
	if (gen.jobs.empty()) return;
	std::cerr << "keygrid-batch: generating " << gen.jobs.size() << " dataset(s) with keygrid-sim\n";
	runProcesses(gen.jobs, spec.batch.jobs, spec.batch.timeoutSeconds, [&](std::size_t j, const ProcessOutcome& o) {
		const std::size_t i = gen.datasetOf[j];
		if (o.succeeded())
			core::writeFileAtomically((out / "_datasets" / spec.datasets[i].name / "generated-by.txt").string(), gen.stamps[j]);
		else
		{
			const std::string why = o.launchError.empty() && !o.timedOut ? reasonFromLog(gen.jobs[j].logPath) : "";
			data[i].error = "generating the dataset failed: " + (why.empty() ? o.describe() : why);
		}
		std::cerr << "keygrid-batch: dataset " << spec.datasets[i].name << " "
				  << (o.succeeded() ? "generated" : "FAILED: " + data[i].error) << " (" << fmtSeconds(o.seconds) << ")\n";
	});
}

/** Datasets: recorded ones as given, synthetic ones generated with keygrid-sim (or reused if
 * generated by the same command from the same scene text); dryRun prints the commands. */
std::vector<PreparedDataset> prepareDatasets(const ExperimentSpec& spec, const std::string& simExe, const fs::path& out, bool dryRun)
{
	std::vector<PreparedDataset> data(spec.datasets.size());
	DatasetGeneration gen;
	for (std::size_t i = 0; i < spec.datasets.size(); i++)
	{
		const DatasetSpec& d = spec.datasets[i];
		if (!d.generated())
		{
			data[i].input = d.input;
			data[i].gt = d.gt;
			if (data[i].gt.empty() && fs::is_regular_file(fs::path(d.input) / "groundtruth.txt"))
				data[i].gt = (fs::path(d.input) / "groundtruth.txt").string();
			continue;
		}
		const fs::path dir = out / "_datasets" / d.name;
		data[i].input = (dir / "tum").string();
		data[i].gt = (dir / "groundtruth.txt").string();
		const ProcessJob job = simJob(d, simExe, dir);
		const std::string stamp = commandText(job.argv) + "\nscene text hash " +
								  std::to_string(std::hash<std::string>{}(mrpt::io::file_get_contents(d.scene))) + "\n";
		if (dryRun)
		{
			std::cout << commandText(job.argv) << "\n";
			continue;
		}
		if (readText((dir / "generated-by.txt").string()) == stamp && fs::is_regular_file(data[i].gt))
		{
			std::cerr << "keygrid-batch: dataset " << d.name << ": reusing " << dir.string() << "\n";
			continue;
		}
		fs::create_directories(dir);
		fs::remove(dir / "generated-by.txt");
		gen.jobs.push_back(job);
		gen.datasetOf.push_back(i);
		gen.stamps.push_back(stamp);
	}
	generateDatasets(spec, out, gen, data);
	return data;
}

/** The run matrix, dataset-major: every run (a failed dataset's runs carry its error) and
 * the keygrid-slam processes of those to run. */
struct RunPlan
{
	std::vector<RunMetrics> runs;
	std::vector<ProcessJob> jobs;
	std::vector<std::size_t> runOf;  //!< jobs[j] -> runs[runOf[j]]
};

RunPlan planRuns(
	const ExperimentSpec& spec, const std::vector<std::string>& configPaths, const std::vector<PreparedDataset>& data,
	const std::string& slamExe, const fs::path& out, bool dryRun)
{
	const int repeats = spec.batch.repeats;
	RunPlan plan;
	for (std::size_t di = 0; di < spec.datasets.size(); di++)
		for (std::size_t ci = 0; ci < spec.configs.size(); ci++)
			for (int r = 1; r <= repeats; r++)
			{
				RunMetrics m;
				m.dataset = spec.datasets[di].name;
				m.config = spec.configs[ci].name;
				m.repeat = r;
				fs::path dir = out / m.dataset / m.config;
				if (repeats > 1) dir /= "r" + std::to_string(r);
				m.runDir = dir.string();
				m.error = data[di].error;
				plan.runs.push_back(m);
				if (!m.error.empty()) continue;
				ProcessJob job;
				job.argv = {slamExe, "--config", configPaths[ci], "--input", data[di].input, "--output", m.runDir, "--quiet"};
				if (!data[di].gt.empty()) job.argv.insert(job.argv.end(), {"--gt", data[di].gt});
				if (spec.datasets[di].maxFrames > 0)
					job.argv.insert(job.argv.end(), {"--max-frames", std::to_string(spec.datasets[di].maxFrames)});
				job.logPath = (dir / "keygrid-slam.log").string();
				if (dryRun)
				{
					std::cout << commandText(job.argv) << "\n";
					continue;
				}
				fs::create_directories(dir);
				fs::remove(dir / "report.json");  // never read a previous batch's report
				plan.jobs.push_back(job);
				plan.runOf.push_back(plan.runs.size() - 1);
			}
	return plan;
}

/** A finished run's metrics from its report.json, else the reason it failed (its log's
 * error line, or how the process ended). */
void collectRunMetrics(RunMetrics& m, const ProcessOutcome& o, const std::string& logPath)
{
	try
	{
		RunMetrics rep = readRunReport(m.runDir + "/report.json");
		rep.dataset = m.dataset;
		rep.config = m.config;
		rep.repeat = m.repeat;
		rep.runDir = m.runDir;
		m = rep;
	}
	catch (const std::exception& e)
	{
		if (o.succeeded()) m.error = e.what();
	}
	m.seconds = o.seconds;
	if (!o.succeeded() && m.error.empty())
	{
		const std::string why = o.launchError.empty() && !o.timedOut ? reasonFromLog(logPath) : "";
		m.error = why.empty() ? o.describe() : why;
	}
}

/** Runs the planned keygrid-slam processes, a progress line per finished run. */
void executeRuns(const ExperimentSpec& spec, const fs::path& out, RunPlan& plan)
{
	const int jobs = spec.batch.jobs, repeats = spec.batch.repeats;
	const std::size_t total = plan.runs.size();
	std::size_t done = total - plan.jobs.size();
	std::cerr << "keygrid-batch: " << plan.jobs.size() << " runs (" << spec.datasets.size() << " datasets x "
			  << spec.configs.size() << " configs x " << repeats << " repeats), " << jobs << " at a time, outputs in "
			  << out.string() << "\n";
	runProcesses(plan.jobs, jobs, spec.batch.timeoutSeconds, [&](std::size_t j, const ProcessOutcome& o) {
		RunMetrics& m = plan.runs[plan.runOf[j]];
		collectRunMetrics(m, o, plan.jobs[j].logPath);
		std::ostringstream line;
		line << "keygrid-batch: " << ++done << " of " << total << " runs done: " << m.dataset << " / " << m.config;
		if (repeats > 1) line << " #" << m.repeat;
		if (m.ok())
		{
			line << ": " << (m.tracked ? *m.tracked : 0) << "/" << (m.frames ? *m.frames : 0) << " tracked";
			if (m.ateRmse) line << ", ATE " << fmtCentimetres(*m.ateRmse);
		}
		else
			line << ": FAILED: " << m.error;
		std::cerr << line.str() << " (" << fmtSeconds(o.seconds) << ")\n";
	});
}

/** results.md's header: the command, when and where it ran, how every run was invoked, and
 * each dataset and config. */
std::string experimentDescriptionMarkdown(
	const ExperimentSpec& spec, const BatchRunOptions& opts, const fs::path& out, const std::string& started, const std::string& machine)
{
	const int jobs = spec.batch.jobs, repeats = spec.batch.repeats;
	std::ostringstream md;
	md << "# " << spec.batch.title << "\n\n"
	   << "Command: `" << opts.commandLine << "` (started " << started << ", " << machine << "; " << jobs
	   << " runs at a time, " << repeats << (repeats > 1 ? " repeats, medians" : " repeat") << ").\n\n"
	   << "Every run: `keygrid-slam --config " << (out / "_configs").string() << "/CONFIG.ini --input INPUT --output "
	   << out.string() << "/DATASET/CONFIG" << (repeats > 1 ? "/rN" : "") << " --gt GT --quiet`.\n\n";
	for (const auto& d : spec.datasets)
		md << "* dataset `" << d.name << "`: "
		   << (d.generated() ? "`keygrid-sim --scene " + d.scene + (d.seed ? " --seed " + std::to_string(*d.seed) : "") +
								   (d.frames ? " --frames " + std::to_string(*d.frames) : "") +
								   (d.simSet.empty() ? "" : " --set '" + d.simSet + "'") + "`"
							 : "`" + d.input + "`")
		   << (d.maxFrames > 0 ? ", first " + std::to_string(d.maxFrames) + " frames" : "") << "\n";
	for (const auto& c : spec.configs)
	{
		md << "* config `" << c.name << "`: `" << c.file << "`";
		for (const auto& o : c.overrides)
			md << (&o == &c.overrides.front() ? " with `" : ", `") << o.section << "." << o.key << " = " << o.value << "`";
		md << "\n";
	}
	return md.str();
}
}  // namespace

std::vector<RunMetrics> runBatch(const ExperimentSpec& spec, const BatchRunOptions& opts)
{
	const std::string bin = opts.binDir.empty() ? selfDir() : opts.binDir;
	const fs::path out(spec.batch.output);
	const std::string started = utcNow(), machine = machineDescription();
	const std::vector<std::string> configPaths = writeConfigCopies(spec, out, opts.dryRun);
	const std::vector<PreparedDataset> data = prepareDatasets(spec, bin + "/keygrid-sim", out, opts.dryRun);
	RunPlan plan = planRuns(spec, configPaths, data, bin + "/keygrid-slam", out, opts.dryRun);
	if (opts.dryRun) return {};
	executeRuns(spec, out, plan);

	const auto rows = aggregateRuns(plan.runs);
	core::writeFileAtomically((out / "results.md").string(), experimentDescriptionMarkdown(spec, opts, out, started, machine) + "\n" + resultsMarkdown(rows));
	core::writeFileAtomically((out / "results.csv").string(), resultsCsv(rows));
	core::writeFileAtomically((out / "runs.csv").string(), runsCsv(plan.runs));
	return plan.runs;
}

int BatchApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-batch", [&] {
		core::CommandLine cl(
			"keygrid-batch",
			"Runs an experiment: every dataset x configuration of EXPERIMENT.ini (format in\n"
			"doc/user-guide.md, \"Batch experiments\") as parallel keygrid-slam processes, after\n"
			"generating the synthetic datasets with keygrid-sim. Writes OUT/results.md and\n"
			"OUT/results.csv (one row per dataset and config, medians over repeats: frames, tracked,\n"
			"fps, ATE RMSE, keyframes, landmarks, loop closures, error), OUT/runs.csv (every run) and\n"
			"each run's outputs in OUT/DATASET/CONFIG[/rN]. Exit code 1 when a run failed.");
		cl.positionals("EXPERIMENT.ini", "the experiment")
			.option("output", "DIR", "output folder, overriding [batch] output")
			.option("jobs", "N", "runs at the same time, overriding [batch] jobs", false, "2")
			.option("repeats", "N", "runs per (dataset, config), overriding [batch] repeats", false, "1")
			.option("bin-dir", "DIR", "folder of keygrid-slam and keygrid-sim", false, "this program's folder")
			.flag("dry-run", "print the commands instead of running them");
		if (!cl.parse(argc, argv)) return 0;
		if (cl.positional().size() != 1) throw core::CommandLineError("expected one EXPERIMENT.ini");
		ExperimentSpec spec = ExperimentSpec::FromFile(cl.positional()[0]);
		if (cl.has("output")) spec.batch.output = cl.get("output");
		if (cl.has("jobs"))
		{
			const long n = cl.getInt("jobs");
			if (n < 1 || n > 64) throw core::CommandLineError("--jobs must be in [1, 64]");
			spec.batch.jobs = static_cast<int>(n);
		}
		if (cl.has("repeats"))
		{
			const long n = cl.getInt("repeats");
			if (n < 1 || n > 1000) throw core::CommandLineError("--repeats must be in [1, 1000]");
			spec.batch.repeats = static_cast<int>(n);
		}
		if (spec.batch.output.empty()) throw core::CommandLineError("no output folder: set [batch] output or give --output");
		BatchRunOptions o;
		if (cl.has("bin-dir")) o.binDir = cl.get("bin-dir");
		o.dryRun = cl.flagSet("dry-run");
		o.commandLine = "keygrid-batch";
		for (int i = 1; i < argc; i++) o.commandLine += std::string(" ") + argv[i];
		const auto runs = runBatch(spec, o);
		if (o.dryRun) return 0;
		std::cout << resultsMarkdown(aggregateRuns(runs)) << "\nresults in " << spec.batch.output << "/results.md and "
				  << spec.batch.output << "/results.csv\n";
		std::size_t failed = 0;
		for (const auto& r : runs) failed += r.ok() ? 0 : 1;
		if (failed)
		{
			std::cerr << "keygrid-batch: " << failed << " of " << runs.size() << " runs failed (reasons in the table)\n";
			return 1;
		}
		return 0;
	});
}

}  // namespace keygrid::slam

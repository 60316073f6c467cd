#include <keygrid/core/CommandLine.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/EvalApp.h>
#include <keygrid/slam/AtomicFile.h>

#include <iostream>

namespace keygrid::slam
{
int EvalApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-eval", [&] {
		core::CommandLine cl(
			"keygrid-eval",
			"Evaluates an estimated TUM trajectory against ground truth: associates poses by\n"
			"timestamp, aligns positions (SE(3) Horn/Umeyama, or Sim(3) with --sim3), and reports\n"
			"the absolute trajectory error (ATE) and the relative pose error (RPE) per second.");
		cl.option("gt", "GT.txt", "ground-truth trajectory (TUM format)", true)
			.option("est", "EST.txt", "estimated trajectory (TUM format)", true)
			.option("json", "OUT.json", "also write the results as JSON (keys ate_rmse_m, rpe_trans_m_per_s, rpe_rot_deg_per_s, matched, ...)")
			.option("max-dt", "SECONDS", "largest timestamp difference for a match", false, "0.02")
			.option("delta", "SECONDS", "RPE time step", false, "1.0")
			.flag("sim3", "align with scale (for monocular or scale-drifting estimates)")
			.flag("skip-bad-lines", "skip malformed lines (reported) instead of failing");
		if (!cl.parse(argc, argv)) return 0;
		eval::TrajectoryErrorOptions opts;
		opts.maxDt = cl.getDouble("max-dt");
		opts.rpeDelta = cl.getDouble("delta");
		opts.withScale = cl.flagSet("sim3");
		std::string why;
		if (!opts.isValid(&why)) throw core::CommandLineError(why);
		core::TrajectoryReadOptions ro;
		ro.skipBadLines = cl.flagSet("skip-bad-lines");
		std::vector<core::TextLineIssue> issues;
		const auto gt = core::readTumTrajectory(cl.get("gt"), ro, &issues);
		const auto est = core::readTumTrajectory(cl.get("est"), ro, &issues);
		for (const auto& is : issues) std::cerr << "keygrid-eval: skipped " << is.str() << "\n";
		const auto res = eval::evaluateTrajectory(gt, est, opts);
		std::cout << res.toText();
		if (cl.has("json")) writeFileAtomically(cl.get("json"), res.toJson());
		return 0;
	});
}

}  // namespace keygrid::slam

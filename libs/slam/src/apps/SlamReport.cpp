#include <keygrid/slam/ProcessMemory.h>
#include <keygrid/slam/System.h>
#include <keygrid/slam/apps/SlamReport.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace keygrid::slam
{
namespace
{
using Json = nlohmann::ordered_json;

/** `x` rounded to `decimals` places: the report shows what the measurement resolves. */
double rounded(double x, int decimals)
{
	const double s = std::pow(10.0, decimals);
	return std::round(x * s) / s;
}

/** Per-stage JSON text of other components (maps, floor, timings, memory) as JSON values. */
Json parsed(const std::string& text) { return Json::parse(text); }

Json relocalizationEvents(const System& sys)
{
	Json events = Json::array();
	for (const auto& f : sys.frames())
		if (f.tracked && f.method == sfm::TrackingMethod::Relocalization)
			events.push_back({{"frame", f.index}, {"keyframe", f.relocalizationKeyFrame}, {"place_recognition", f.relocalizedByPlaceRecognition}});
	return events;
}

Json loopClosures(const System& sys)
{
	Json loops = Json::array();
	for (const auto& ev : sys.loopClosures())
	{
		loops.push_back({{"frame", ev.frameIndex},
						 {"keyframe", ev.keyframe},
						 {"loop_keyframe", ev.loopKeyFrame},
						 {"keyframe_timestamp", rounded(ev.keyframeTimestamp, 6)},
						 {"loop_keyframe_timestamp", rounded(ev.loopKeyFrameTimestamp, 6)},
						 {"score", rounded(ev.score, 4)},
						 {"inliers", ev.inliers},
						 {"measured_distance_m", rounded(ev.measuredDistance, 4)},
						 {"measured_angle_deg", rounded(ev.measuredAngleDeg, 3)},
						 {"correction_m", rounded(ev.correctionMetres, 4)},
						 {"seconds", rounded(ev.seconds, 4)}});
		// A monocular loop is a similarity: the scale it gave the current keyframe's part of the map.
		if (sys.config().sensor == Sensor::Monocular) loops.back()["scale_correction"] = rounded(ev.scaleCorrection, 4);
	}
	return loops;
}

/** One object for what was loaded (--load-map), recorded (--map), or both (extend mode). */
std::optional<Json> session(const System& sys, const SlamReportInput& in)
{
	const auto st = sys.stats();
	const SessionRecorder* rec = sys.recorder();
	if (!in.loaded && !rec) return std::nullopt;
	Json s = Json::object();
	if (in.loaded)
	{
		s["loaded"] = in.options.loadMap;
		s["mode"] = in.options.localize ? "localize" : "extend";
		s["keyframes"] = in.loaded->keyframes;
		s["landmarks"] = in.loaded->landmarks;
		s["load_s"] = rounded(in.loaded->seconds, 3);
		s["localized"] = st.tracked;
		s["lost"] = st.lost;
		s["localized_ratio"] = rounded(st.frames ? static_cast<double>(st.tracked) / static_cast<double>(st.frames) : 0.0, 4);
		if (!in.options.localize)
		{
			const auto ex = sys.extendState();
			s["started"] = ex.startedInStoredMap ? "in_stored_map" : ex.startedNewMap ? "new_map" : "never";
			s["maps_merged"] = st.mapsMerged;
			s["keyframes_waiting_for_merge"] = ex.waitingForMerge;
		}
	}
	if (rec)
	{
		const auto rs = rec->stats();
		const auto ws = rec->writerStats();
		std::error_code ec;
		const auto bytes = std::filesystem::file_size(rec->path(), ec);
		s["recorded"] = rec->path();
		s["updates"] = rs.updates;
		s["keyframes_written"] = rs.keyframesWritten;
		s["landmarks_written"] = rs.landmarksWritten;
		s["snapshots"] = rs.snapshots;
		s["build_ms_per_update"] = rounded(rs.updates ? 1e3 * rs.buildSeconds / static_cast<double>(rs.updates) : 0.0, 3);
		s["writer_encode_s"] = rounded(ws.encodeSeconds, 3);
		s["writer_commit_s"] = rounded(ws.writeSeconds, 3);
		s["file_mb"] = rounded(ec ? 0.0 : static_cast<double>(bytes) / (1024.0 * 1024.0), 3);
	}
	return s;
}

/** What gives the map its scale and, monocular, how the map started. */
void addScale(Json& js, const System& sys, const SlamConfig& cfg)
{
	const auto st = sys.stats();
	// Measured depth, or nothing (monocular: arbitrary units).
	const MetricScale* ms = sys.metricScale();
	js["scale_source"] = cfg.sensor == Sensor::Rgbd ? "depth" : ms && ms->metric() ? "camera_height" : "none";
	if (ms)
		js["camera_height_scale"] = {{"camera_height_m", cfg.metricScale.estimator.cameraHeight},
									 {"estimates", ms->stats().estimates},
									 {"applied", ms->stats().applied},
									 {"total_factor", ms->stats().totalFactor},
									 {"last_factor", ms->stats().lastFactor},
									 {"last_message", ms->stats().lastMessage}};
	if (cfg.sensor == Sensor::Monocular)
		js["initialization"] = {{"started", st.framesToInitialize > 0},
								{"frames", st.framesToInitialize > 0 ? Json(st.framesToInitialize) : Json()},
								{"frame", st.framesToInitialize > 0 ? Json(st.initializationFrame) : Json()}};
}

/** How the frames went: tracked, lost, relocalized; what the input skipped or dropped. */
void addTracking(Json& js, const System& sys, const SlamReportInput& in)
{
	const auto st = sys.stats();
	js["frames"] = st.frames;
	js["tracked"] = st.tracked;
	js["lost"] = st.lost;
	js["relocalizations"] = st.relocalizations;
	js["relocalization_events"] = relocalizationEvents(sys);
	js["pnp_fallbacks"] = st.pnpFallbacks;
	js["skipped_input_entries"] = in.result.skipped;
	if (!in.result.lastSkip.empty()) js["last_skip_reason"] = in.result.lastSkip;
	js["interrupted"] = in.result.interrupted;
	if (in.live) js["live"] = {{"grabbed", in.result.liveGrabbed}, {"dropped", in.result.liveDropped}};
}

/** The sparse map's size and upkeep (culling, fusion, HOC), loops, session and metric maps. */
void addMap(Json& js, const System& sys, const SlamReportInput& in)
{
	const auto st = sys.stats();
	js["keyframes"] = sys.map().numKeyFrames();
	js["keyframes_created"] = st.keyframesCreated;
	js["keyframes_culled"] = st.keyframesCulled;
	js["landmarks"] = sys.map().numLandmarks();
	js["landmarks_culled"] = st.landmarksCulled;
	js["landmarks_fused"] = st.landmarksFused;
	if (in.config.mode == RunMode::Threaded) js["ba_discarded"] = st.baDiscarded;
	if (in.config.tracker.hoc.enabled)
		js["hoc"] = {{"landmarks_pruned", st.landmarksPrunedHoc}, {"increments", st.hocIncrements}, {"decrements", st.hocDecrements},
					 {"occluded", st.hocOccluded},		{"recovered", st.hocRecovered},	   {"seen_through", st.hocSeenThrough},
					 {"fallback_frames", st.hocFallbackFrames}};
	if (sys.loopCloser()) js["vocabulary"] = sys.loopCloser()->vocabularySource();
	js["loop_closures"] = loopClosures(sys);
	if (auto s = session(sys, in)) js["session"] = std::move(*s);
	js["maps"] = sys.metricMaps() ? parsed(sys.metricMaps()->summaryJson()) : Json::array();
	js["floor"] = sys.metricMaps() ? parsed(sys.metricMaps()->floorJson()) : Json();
}

/** Means per frame and per keyframe (bundle adjustment), the final refinement. */
void addOptimization(Json& js, const System& sys)
{
	const auto st = sys.stats();
	const double kfs = static_cast<double>(std::max<std::size_t>(1, st.keyframesCreated));
	js["mean_inliers"] = rounded(st.sumInliers / static_cast<double>(std::max<std::size_t>(1, st.frames)), 1);
	js["mean_ba_keyframes"] = rounded(st.sumBaKeyFrames / kfs, 1);
	js["mean_ba_observations"] = rounded(st.sumBaObservations / kfs, 1);
	js["mean_ba_outliers"] = rounded(st.sumBaOutliers / kfs, 1);
	js["mean_ba_iterations"] = rounded(st.sumBaIterations / kfs, 2);
	if (const auto& ba = sys.globalBundleAdjustmentReport())
		js["global_ba"] = {{"keyframes", ba->keyframes},		{"landmarks", ba->landmarks}, {"landmarks_left_out", ba->landmarksLeftOut}, {"observations", ba->observations},
						   {"outliers", ba->outliersRemoved}, {"iterations", ba->iterations}, {"median_chi2", rounded(ba->medianChi2, 4)},
						   {"scale_undone", rounded(sys.finalScaleUndone(), 6)}};
	if (const auto& shift = sys.finalMapShift())
		js["final_map_shift"] = {{"largest_m", rounded(shift->largest, 5)}, {"reanchored", shift->reanchored}};
}

/** Speed, timings, memory, and how the per-frame cost evolves along the run. */
void addCost(Json& js, const System& sys, const SlamReportInput& in)
{
	js["fps"] = rounded(in.result.fps, 3);
	js["wall_time_s"] = rounded(in.wallSeconds, 3);
	js["timings"] = parsed(sys.timings().toJson(2));
	// tests/benchmarks/slam/office_loop_memory.sh reads the memory growth.
	js["max_rss_mb"] = rounded(peakResidentMegabytes(), 1);
	js["rss_mb_by_keyframes"] = parsed(in.memory.toJson());
	Json blocks = Json::array();
	for (const double b : sys.timings().blockMeans("track_and_map", 100)) blocks.push_back(rounded(1e3 * b, 2));
	js["track_and_map_ms_per_100_frames"] = blocks;
}

/** --gt: the trajectory's errors against ground truth. */
void addErrors(Json& js, const System& sys, const eval::TrajectoryErrors& e)
{
	// A map without metric scale (monocular): after a Sim(3) alignment, whose scale (metres
	// per map unit) is recorded.
	const bool sim3 = !sys.metricUnits();
	js["ate_alignment"] = sim3 ? "sim3" : "se3";
	if (sim3) js["ate_sim3_scale"] = e.alignment.s;
	js["ate_rmse_m"] = e.ate.rmse;
	js["ate_rot_rmse_deg"] = e.ateRotDeg.rmse;
	if (e.rpeTrans)
	{
		js["rpe_trans_m_per_s"] = e.rpeTrans->rmse;
		js["rpe_rot_deg_per_s"] = e.rpeRotDeg->rmse;
	}
	js["gt_matched"] = e.matched;
}
}  // namespace

std::string slamReportJson(const System& sys, const SlamReportInput& in)
{
	Json js;
	js["input"] = in.input;
	js["config"] = in.options.configPath;
	js["config_set"] = in.options.set.empty() ? Json() : Json(in.options.set);
	js["mode"] = toString(in.config.mode);
	js["sensor"] = toString(in.config.sensor);
	// Recorded inputs: the pace the frames were released at (0: as fast as processed).
	js["playback_rate"] = in.live ? Json() : Json(in.config.playbackRate);
	addScale(js, sys, in.config);
	addTracking(js, sys, in);
	addMap(js, sys, in);
	addOptimization(js, sys);
	addCost(js, sys, in);
	if (in.errors) addErrors(js, sys, *in.errors);
	js["output_errors"] = in.outputErrors;
	js["error"] = in.result.error.empty() ? Json() : Json(in.result.error);
	// Invalid UTF-8 (a damaged file's bytes quoted in an error) is replaced, not thrown.
	return js.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace keygrid::slam

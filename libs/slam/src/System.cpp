#include <keygrid/maps/ExportFrame.h>
#include <keygrid/sfm/BundleWindow.h>
#include <keygrid/slam/FinalRefinement.h>
#include <keygrid/slam/StoredKeyFrameImages.h>
#include <keygrid/slam/System.h>

#include <chrono>
#include <future>
#include <set>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
double secondsSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

System::System(const SlamConfig& cfg)
	: m_cfg(cfg),
	  m_extractor(cfg.features),
	  m_tracker(m_map, cfg.tracker),
	  m_mapper(m_map, cfg.mapping, cfg.tracker.matcher),
	  m_images(std::make_unique<KeyFrameImageCache>(static_cast<std::size_t>(cfg.store.imageCacheMib) << 20))
{
	if (cfg.sensor == Sensor::Monocular && cfg.metricScale.enabled()) m_metricScale.emplace(cfg.metricScale);
	if (cfg.loop.enabled)
	{
		m_loopCloser = std::make_unique<loop::LoopCloser>(m_map, m_mapper, cfg.loop, cfg.tracker.matcher, cfg.features.type);
		// Relocalization asks the loop closer's keyframe database (vocabulary tree) first.
		m_tracker.setPlaceRecognizer([this](const sfm::FrameFeatures& f, int n) { return m_loopCloser->placeCandidates(f.descriptors, n); });
	}
	if (cfg.mode == RunMode::Threaded)
	{
		// A few keyframes may wait for local mapping; beyond that tracking waits (back pressure
		// instead of an ever longer backlog on a slow machine).
		m_mappingQueue = std::make_unique<core::BoundedQueue<KeyFrameJob>>(4);
		m_loopQueue = std::make_unique<core::BoundedQueue<KeyFrameJob>>(16);
		if (const double share = cfg.deferralRatio(); share > 0)
			m_tracker.deferKeyFramesWhile(
				[this]
				{
					std::lock_guard<std::mutex> lk(m_statsMutex);
					return m_jobsMapped < m_jobsQueued;
				},
				share);
		m_mapping = std::thread([this] { mappingThread(); });
		m_loopClosing = std::thread([this] { loopClosingThread(); });
	}
}

System::~System() { joinThreads(); }

void System::noteRunAttributes()
{
	if (const auto share = m_tracker.recentShareMedian())
		m_recorder->setAttribute(kTrackingShareAttribute, std::to_string(*share));
	if (m_maps && m_maps->T_world_floor()) m_recorder->setAttribute(kFloorAttribute, maps::poseMatrixText(*m_maps->T_world_floor()));
}

LoadedSession System::loadSession(const store::SessionStore& session, bool localizeOnly)
{
	if (!m_frames.empty()) throw std::logic_error("System::loadSession: a session is loaded before the first frame");
	std::lock_guard<std::mutex> lock(m_map.mutex());
	const auto loaded = loadSparseMap(session, m_map);
	m_localizeOnly = localizeOnly;
	m_extending = !localizeOnly;
	m_tracker.startInLoadedMap();
	m_tracker.setKeyFrameInsertion(!localizeOnly);
	// The first relocalization is judged against the share the mapping run's tracking matched.
	if (const auto it = session.meta().attributes.find(kTrackingShareAttribute); it != session.meta().attributes.end())
	{
		const double share = std::strtod(it->second.c_str(), nullptr);
		if (share > 0 && share <= 1) m_tracker.seedRecentShare(share);
	}
	if (m_loopCloser)
	{
		// A vocabulary trained in the mapping run exists only in the file.
		if (m_loopCloser->vocabularyFile().empty() && session.hasStoredVocabulary())
			m_loopCloser->useVocabulary(*session.loadVocabulary(), "stored in " + session.path());
		m_loopCloser->indexKeyFrames();
	}
	if (m_extending) reintegrateLoadedKeyFrames(session);
	return loaded;
}

void System::reintegrateLoadedKeyFrames(const store::SessionStore& session)
{
	// The camera path goes on from the stored run's (the 3D grid compares voxels by the path
	// length at which they were seen): along the keyframes, in the order they were made.
	const StoredKeyFrameImages stored(session);
	std::optional<Eigen::Vector3d> last;
	for (auto& [id, kf] : m_map.keyframes())
	{
		const Eigen::Vector3d c = kf.cameraCenter();
		if (last) m_travelled += (c - *last).norm();
		last = c;
		if (!m_maps) continue;
		// The images come back for the dense maps and keyframes.simplemap.
		auto img = stored.load(kf);
		auto& k = m_map.keyframe(id);
		k.colour = std::move(img.colour);
		k.depth = std::move(img.depth);
		m_maps->insertKeyFrame(m_map, id, m_travelled);
	}
	if (m_maps) m_maps->syncLandmarks(m_map, m_cfg.tracker.hoc);
	releaseKeyFrameImages();
}

void System::releaseKeyFrameImages()
{
	for (auto& [id, kf] : m_map.keyframes())
	{
		if (kf.mapId != 0 || (kf.depth.empty() && kf.colour.empty())) continue;
		m_images->put(id, {kf.depth, kf.colour});
		auto& k = m_map.keyframe(id);
		k.depth.release();
		k.colour.release();
	}
}

sfm::FrameFeatures System::extract(const core::Frame& frame) const { return m_extractor.extract(frame); }

const sfm::TrackedFrame& System::process(const core::Frame& frame)
{
	const auto t0 = std::chrono::steady_clock::now();
	auto f = extract(frame);
	m_timings.add("extract", secondsSince(t0));
	return processExtracted(frame, std::move(f));
}

const sfm::TrackedFrame& System::processExtracted(const core::Frame& frame, sfm::FrameFeatures features)
{
	throwIfBackgroundFailed();
	std::unique_lock<std::mutex> lock(m_map.mutex());
	auto t0 = std::chrono::steady_clock::now();
	const sfm::PinholeIntrinsics K = features.camera.pinhole();
	if (!m_K) m_K = K;
	sfm::TrackedFrame tf = m_tracker.track(frame, std::move(features));
	m_timings.add("track", secondsSince(t0));
	if (m_cfg.tracker.hoc.enabled) m_timings.add("hoc", tf.hocSeconds);
	if (!tf.initMessage.empty()) logInitialization(tf);
	// Monocular map start: the first keyframe (the reference frame, at the origin) is mapped
	// before the second, and the path starts there.
	std::optional<KeyFrameJob> initialJob;
	if (tf.hasInitialKeyFrame)
	{
		initialJob = KeyFrameJob{tf.initialKeyFrame, tf.initialFrameIndex, m_travelled, K};
		m_lastTrackedPose = m_map.keyframe(tf.initialKeyFrame).T_world_cam;
		attachInitialKeyFrame(tf);
	}
	// A loop closed on another thread moved the map: the path length restarts from here.
	if (m_map.corrections() != m_correctionsSeen)
	{
		m_correctionsSeen = m_map.corrections();
		m_lastTrackedPose.reset();
	}
	if (tf.tracked)
	{
		if (m_lastTrackedPose) m_travelled += (tf.T_world_cam.translation() - m_lastTrackedPose->translation()).norm();
		m_lastTrackedPose = tf.T_world_cam;
	}
	const KeyFrameJob job{tf.keyframe, tf.index, m_travelled, K};
	if (tf.newKeyFrame && !m_mappingQueue)
	{
		if (initialJob)
		{
			mapKeyFrame(*initialJob);
			insertAndCloseLoops(*initialJob, nullptr);
		}
		mapKeyFrame(job);
		insertAndCloseLoops(job, &tf);
	}
	if (m_extending && !m_startedInStoredMap && !m_startedNewMap) startExtending(tf);
	if (m_metricScale && tf.newKeyFrame) applyMetricScale(&tf);
	tf.mapLandmarks = m_map.numLandmarks();
	lock.unlock();
	countFrame(tf);
	const bool queueKeyFrame = tf.newKeyFrame && m_mappingQueue;
	m_frames.push_back(std::move(tf));
	if (queueKeyFrame && initialJob) queueForMapping(*initialJob);
	if (queueKeyFrame)
	{
		queueForMapping(job);
		// A keyframe tracking had to insert while local mapping was busy: the next frames
		// track against its landmarks (SlamConfig::waitsForWeakKeyFrames).
		const bool waitAll = m_frames.back().keyFrameWhileMappingBusy && m_cfg.waitsForWeakKeyFrames();
		waitForMapping(waitAll ? 0 : static_cast<std::size_t>(m_cfg.mappingLag));
	}
	return m_frames.back();
}

void System::countFrame(const sfm::TrackedFrame& tf)
{
	std::lock_guard<std::mutex> lk(m_statsMutex);
	m_stats.landmarksPrunedHoc += tf.hoc.pruned;
	m_stats.hocIncrements += tf.hoc.incremented;
	m_stats.hocDecrements += tf.hoc.decremented;
	m_stats.hocOccluded += tf.hoc.occluded;
	m_stats.hocRecovered += tf.hoc.recovered;
	m_stats.hocSeenThrough += tf.hoc.seenThrough;
	if (tf.hocFallback) m_stats.hocFallbackFrames++;
	m_stats.frames++;
	m_stats.sumInliers += tf.inliers;
	if (tf.tracked) m_stats.tracked++;
	else
		m_stats.lost++;
	if (tf.method == sfm::TrackingMethod::Relocalization && tf.tracked) m_stats.relocalizations++;
	if (tf.method == sfm::TrackingMethod::Pnp && tf.tracked) m_stats.pnpFallbacks++;
	if (tf.hasInitialKeyFrame)
	{
		m_stats.framesToInitialize = m_stats.frames;
		m_stats.initializationFrame = tf.index;
	}
}

void System::logInitialization(const sfm::TrackedFrame& tf)
{
	// Every change of reference and the start are logged; repeated failures with one
	// reference once per kEvery frames, and no more than kMaxLines lines in all.
	constexpr std::size_t kEvery = 10, kMaxLines = 500;
	const bool always = tf.hasInitialKeyFrame || tf.initNewReference;
	const bool due = m_initLog.empty() || tf.index >= m_initLogLastFrame + kEvery;
	if (m_initLog.size() >= kMaxLines || !(always || due))
	{
		++m_initLogSkipped;
		m_initLogLastMessage = tf.initMessage;
		return;
	}
	std::string line = tf.initMessage;
	if (m_initLogSkipped) line += " [" + std::to_string(m_initLogSkipped) + " messages left out before]";
	m_initLog.push_back(std::move(line));
	m_initLogLastFrame = tf.index;
	m_initLogSkipped = 0;
}

void System::applyMetricScale(sfm::TrackedFrame* tf)
{
	const auto t0 = std::chrono::steady_clock::now();
	const auto r = m_metricScale->update(m_map);
	m_timings.add("metric_scale", secondsSince(t0));
	if (!r) return;
	// Loops now keep the map's metres (LoopCloser::setMetricUnits).
	if (m_loopCloser) m_loopCloser->setMetricUnits(true);
	// A bundle adjustment solved meanwhile (threaded mode) was solved at the old scale.
	m_map.noteCorrection();
	m_correctionsSeen = m_map.corrections();
	if (r->wholeMap())
		followWholeMapRescale(r->factor, tf);
	else
		followWindowRescale(*r, tf);
}

void System::followWholeMapRescale(double s, sfm::TrackedFrame* tf)
{
	m_tracker.onMapRescaled(s);
	if (tf)
	{
		sfm::scaleTranslation(tf->T_world_cam, s);
		sfm::scaleTranslation(tf->T_ref_cam, s);
	}
	for (auto& f : m_frames)
	{
		sfm::scaleTranslation(f.T_world_cam, s);
		sfm::scaleTranslation(f.T_ref_cam, s);
	}
	m_travelled *= s;
	if (m_lastTrackedPose) sfm::scaleTranslation(*m_lastTrackedPose, s);
	// The maps follow: what they hold is rebuilt in the new scale, on the estimate's floor.
	if (m_maps && m_metricScale->floorPlane())
	{
		const auto& floor = *m_metricScale->floorPlane();
		for (const auto& [name, sec] : m_maps->applyRescale(m_map, s, floor.normal, floor.offset))
			m_timings.add("map_correction:" + name, sec);
	}
}

void System::followWindowRescale(const MetricScale::Rescale& r, sfm::TrackedFrame* tf)
{
	// A frame keeps its offset from its reference keyframe, grown by that keyframe's factor.
	const auto follow = [&](sfm::TrackedFrame& f)
	{
		const auto it = r.newScales.find(f.reference);
		if (!f.hasReference || it == r.newScales.end()) return;
		sfm::scaleTranslation(f.T_ref_cam, it->second);
		f.T_world_cam = r.newPoses.at(f.reference) + f.T_ref_cam;
	};
	// The tracker's reference is the newest keyframe, which took the full factor.
	m_tracker.onMapRescaledLocally(r.factor);
	if (tf)
	{
		follow(*tf);
		m_lastTrackedPose = tf->T_world_cam;
	}
	else
		m_lastTrackedPose.reset();
	for (auto& f : m_frames) follow(f);
	if (m_maps && m_metricScale->floorPlane())
	{
		const auto& floor = *m_metricScale->floorPlane();
		m_maps->setFloorFromCameraHeight(floor.normal, floor.offset);
		for (const auto& [name, sec] : m_maps->applyCorrection(r.newPoses, r.newScales))
			m_timings.add("map_correction:" + name, sec);
	}
}

void System::attachInitialKeyFrame(const sfm::TrackedFrame& tf)
{
	for (auto it = m_frames.rbegin(); it != m_frames.rend(); ++it)
	{
		if (it->index != tf.initialFrameIndex) continue;
		it->hasReference = true;
		it->reference = tf.initialKeyFrame;
		it->T_ref_cam = mrpt::poses::CPose3D();
		it->T_world_cam = m_map.keyframe(tf.initialKeyFrame).T_world_cam;
		return;
	}
}

void System::mapKeyFrame(const KeyFrameJob& job)
{
	const auto t0 = std::chrono::steady_clock::now();
	const auto rep = m_mapper.process(job.keyframe, job.K);
	recordLocalMapping(rep, secondsSince(t0));
}

bool System::mapKeyFrameConcurrently(const KeyFrameJob& job)
{
	const auto t0 = std::chrono::steady_clock::now();
	std::unique_lock<std::mutex> lock(m_map.mutex());
	if (!m_map.hasKeyFrame(job.keyframe)) return false;
	auto pass = m_mapper.prepare(job.keyframe, job.K);
	lock.unlock();
	pass.solve();  // on the pass's copies: tracking and loop closing go on meanwhile
	lock.lock();
	const auto rep = m_mapper.complete(std::move(pass));
	recordLocalMapping(rep, secondsSince(t0));
	return true;
}

void System::recordLocalMapping(const sfm::LocalMappingReport& rep, double seconds)
{
	m_timings.add("local_mapping", seconds);
	for (const auto& [stage, sec] : rep.stageSeconds) m_timings.add("local_mapping:" + stage, sec);
	std::lock_guard<std::mutex> lk(m_statsMutex);
	m_stats.keyframesCreated++;
	m_stats.keyframesCulled += rep.culledKeyFrames;
	m_stats.landmarksCulled += rep.culledLandmarks;
	m_stats.landmarksFused += rep.fusedLandmarks;
	m_stats.sumBaKeyFrames += rep.ba.keyframes;
	m_stats.sumBaObservations += rep.ba.observations;
	m_stats.sumBaOutliers += rep.ba.outliersRemoved;
	m_stats.sumBaIterations += rep.ba.iterations;
	m_stats.baDiscarded += rep.baDiscarded ? 1 : 0;
}

void System::startExtending(const sfm::TrackedFrame& tf)
{
	// Map lock held. Relocalized in the stored map: the camera is back in mapped space.
	if (tf.tracked)
	{
		m_startedInStoredMap = true;
		if (m_maps) m_maps->notifyLoopClosure();
		return;
	}
	const int limit = m_cfg.store.newMapAfterLostFrames;
	if (limit > 0 && ++m_lostAtStart >= static_cast<std::size_t>(limit))
	{
		// The stored map has no place like this: map on in a provisional frame until loop
		// closing finds a common place and merges the two (LoopCloser).
		m_tracker.startNewMap();
		m_startedNewMap = true;
		m_lastTrackedPose.reset();
	}
}

void System::insertAndCloseLoops(const KeyFrameJob& job, sfm::TrackedFrame* tf)
{
	if (!m_map.hasKeyFrame(job.keyframe)) return;  // culled by local mapping
	if (m_maps)
	{
		const auto t0 = std::chrono::steady_clock::now();
		// A keyframe of a map not merged yet waits: its pose is in a provisional frame.
		if (m_map.keyframe(job.keyframe).mapId != 0)
			m_waitingForMerge.push_back(job);
		else
			m_maps->insertKeyFrame(m_map, job.keyframe, job.travelled);
		// The landmark maps (hocPointsMap) are copies of the frontend's landmarks that only the
		// session store's snapshots and the final outputs read: copied when a snapshot is due
		// and in finish(), not at every keyframe (a copy costs the whole map).
		if (m_recorder && m_recorder->snapshotDueAtNextKeyFrame())
		{
			const auto t1 = std::chrono::steady_clock::now();
			m_maps->syncLandmarks(m_map, m_cfg.tracker.hoc);
			m_timings.add("map_insertion:sync_landmarks", secondsSince(t1));
		}
		m_timings.add("map_insertion", secondsSince(t0));
	}
	const auto ev = closeLoops(job, tf);
	if (ev && ev->mergedMap && m_maps)
	{
		const auto t0 = std::chrono::steady_clock::now();
		// The merged keyframes go in (culled ones are dropped); another map's keep waiting.
		std::vector<KeyFrameJob> stillWaiting;
		for (const auto& w : m_waitingForMerge)
		{
			if (!m_map.hasKeyFrame(w.keyframe)) continue;
			if (m_map.keyframe(w.keyframe).mapId == 0)
				m_maps->insertKeyFrame(m_map, w.keyframe, w.travelled);
			else
				stillWaiting.push_back(w);
		}
		m_waitingForMerge.swap(stillWaiting);
		m_maps->syncLandmarks(m_map, m_cfg.tracker.hoc);
		m_timings.add("map_insertion", secondsSince(t0));
	}
	if (ev && ev->mergedMap)
	{
		std::lock_guard<std::mutex> lk(m_statsMutex);
		m_stats.mapsMerged++;
	}
	if (m_recorder)
	{
		const auto t0 = std::chrono::steady_clock::now();
		noteRunAttributes();
		m_recorder->afterKeyFrame(m_map, m_loopCloser.get(), ev ? &*ev : nullptr, m_maps.get());
		m_timings.add("session_store", secondsSince(t0));
	}
	{
		const auto t0 = std::chrono::steady_clock::now();
		releaseKeyFrameImages();
		m_timings.add("image_spill", secondsSince(t0));
	}
	if (!ev) return;
	std::lock_guard<std::mutex> lk(m_statsMutex);
	m_loops.push_back(*ev);
}

std::optional<loop::LoopClosureEvent> System::closeLoops(const KeyFrameJob& job, sfm::TrackedFrame* tf)
{
	if (!m_loopCloser) return std::nullopt;
	const auto t0 = std::chrono::steady_clock::now();
	auto ev = m_loopCloser->process(job.keyframe, job.frameIndex, job.K);
	m_timings.add("loop_closing", secondsSince(t0));
	if (!ev) return std::nullopt;
	// A Sim(3) correction rescales the map around the loop: the camera-height scale is
	// measured again on the corrected map at the next keyframe (the correction itself keeps
	// the units of the first keyframe, so the two do not pull the scale against each other).
	if (m_metricScale) m_metricScale->requestEstimate();
	PoseCorrection c{PoseCorrection::Source::LoopClosure, ev->newPoses, job.keyframe, &ev->newScales};
	for (const auto& [name, sec] : publishCorrection(c, tf)) m_timings.add(name, sec);
	return ev;
}

std::map<std::string, double> System::publishCorrection(const PoseCorrection& c, sfm::TrackedFrame* tf)
{
	if (c.source == PoseCorrection::Source::LoopClosure)
	{
		// The tracker: its last pose (and threaded tracking's check for corrections).
		m_map.noteCorrection();
		if (tf)
		{
			// Sequential: the frame that created the keyframe is the tracker's last frame.
			m_tracker.onMapCorrected(m_map.keyframe(c.keyframe).T_world_cam);
			tf->T_world_cam = m_map.keyframe(c.keyframe).T_world_cam;
			m_lastTrackedPose = tf->T_world_cam;
			m_correctionsSeen = m_map.corrections();
		}
		else
			m_tracker.onMapCorrected();  // tracking went on: its last frame follows its reference
	}
	// The frames follow their reference keyframes by themselves (trajectory()); the metric
	// maps are re-anchored.
	std::map<std::string, double> seconds;
	if (!m_maps) return seconds;
	const std::map<sfm::KeyFrameId, double> noScales;
	const std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>> noPoints;
	for (const auto& [name, sec] : m_maps->applyCorrection(c.newPoses, c.newScales ? *c.newScales : noScales, c.newPoints ? *c.newPoints : noPoints))
		seconds["map_correction:" + name] = sec;
	if (c.source == PoseCorrection::Source::LoopClosure) m_maps->notifyLoopClosure();
	return seconds;
}

void System::queueForMapping(const KeyFrameJob& job)
{
	if (!m_mappingQueue->push(job)) throwIfBackgroundFailed();
	std::lock_guard<std::mutex> lk(m_statsMutex);
	m_jobsQueued++;
}

void System::waitForMapping(std::size_t lag)
{
	const auto t0 = std::chrono::steady_clock::now();
	std::unique_lock<std::mutex> lk(m_statsMutex);
	m_jobMapped.wait(lk, [&] { return m_jobsMapped + lag >= m_jobsQueued || !m_backgroundError.empty(); });
	lk.unlock();
	m_timings.add("mapping_wait", secondsSince(t0));
	throwIfBackgroundFailed();
}

void System::mappingThread()
{
	// A job counts as mapped once processed or skipped; if it throws, setBackgroundError wakes
	// a waiting tracker instead.
	const auto jobDone = [this]
	{
		{
			std::lock_guard<std::mutex> lk(m_statsMutex);
			m_jobsMapped++;
		}
		m_jobMapped.notify_all();
	};
	try
	{
		while (auto job = m_mappingQueue->pop())
		{
			// A keyframe still queued may have been culled as redundant meanwhile.
			const bool exists = mapKeyFrameConcurrently(*job);
			jobDone();
			if (exists && !m_loopQueue->push(*job)) break;
		}
	}
	catch (const std::exception& e)
	{
		setBackgroundError(std::string("local mapping: ") + e.what());
	}
	m_loopQueue->close();
}

void System::loopClosingThread()
{
	try
	{
		while (auto job = m_loopQueue->pop())
		{
			std::lock_guard<std::mutex> lock(m_map.mutex());
			insertAndCloseLoops(*job, nullptr);
		}
	}
	catch (const std::exception& e)
	{
		setBackgroundError(std::string("loop closing: ") + e.what());
	}
}

void System::setBackgroundError(const std::string& what)
{
	{
		std::lock_guard<std::mutex> lk(m_statsMutex);
		if (m_backgroundError.empty()) m_backgroundError = what;
	}
	m_jobMapped.notify_all();  // tracking may be waiting for local mapping
	// Nothing more is accepted: tracking's next push fails and reports the error.
	m_mappingQueue->close();
	m_loopQueue->close();
}

void System::throwIfBackgroundFailed() const
{
	const std::string e = backgroundError();
	if (!e.empty()) throw std::runtime_error(e);
}

std::string System::backgroundError() const
{
	std::lock_guard<std::mutex> lk(m_statsMutex);
	return m_backgroundError;
}

SystemStats System::stats() const
{
	std::lock_guard<std::mutex> lk(m_statsMutex);
	return m_stats;
}

std::size_t System::numKeyFrames() const
{
	std::lock_guard<std::mutex> lk(m_map.mutex());
	return m_map.numKeyFrames();
}

void System::joinThreads()
{
	if (!m_mappingQueue) return;
	m_mappingQueue->close();  // the queued keyframes are still mapped, then loop-closed
	if (m_mapping.joinable()) m_mapping.join();
	if (m_loopClosing.joinable()) m_loopClosing.join();
}

void System::finish()
{
	joinThreads();
	// The last initialization message left out by the rate bound: a sequence that never
	// starts a map ends with why.
	if (m_initLogSkipped > 0 && !m_initLogLastMessage.empty())
	{
		m_initLog.push_back(m_initLogLastMessage + " [" + std::to_string(m_initLogSkipped - 1) + " messages left out before]");
		m_initLogSkipped = 0;
	}
	if (m_finished || !m_K || m_map.numKeyFrames() == 0) return;
	m_finished = true;
	// A loop correction near the end asked for a new scale estimate that no keyframe came to run.
	if (m_metricScale && m_metricScale->estimateRequested())
	{
		std::lock_guard<std::mutex> lock(m_map.mutex());
		applyMetricScale(nullptr);
	}
	// Keyframe poses before the refinement (erased keyframes via their parents).
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> before;
	for (const auto& [id, kf] : m_map.keyframes()) before[id] = kf.T_world_cam;  // also a loaded map's
	for (const auto& f : m_frames)
	{
		mrpt::poses::CPose3D T;
		if (f.newKeyFrame && m_map.poseOf(f.keyframe, T)) before[f.keyframe] = T;
	}
	const auto window = adjustFinalMap();
	// The maps' re-anchoring and the frames' re-estimation only read the adjusted map: they
	// run side by side. The maps stay on this thread, whose heap still holds what the bundle
	// adjustment freed (a new thread would allocate their rebuilt grids in a fresh malloc arena).
	auto refinement = std::async(std::launch::async, [&] { refineFrames(window); });
	const auto mapTimes = reanchorMaps(before);
	refinement.get();
	for (const auto& [name, sec] : mapTimes) m_timings.add(name, sec);
	if (m_recorder) storeFinalSession();
}

std::optional<std::set<sfm::KeyFrameId>> System::adjustFinalMap()
{
	const auto t0 = std::chrono::steady_clock::now();
	// Bounded: the keyframes around the closed loops and the newest ones move (see
	// sfm::growBundleWindow); unbounded (small map or global_max_keyframes = 0): every one.
	std::optional<std::set<sfm::KeyFrameId>> window;
	if (m_cfg.refinement.globalBundleAdjustment && m_map.numKeyFrames() > 1 && !m_localizeOnly)
	{
		auto ba = finalBundleAdjustment(m_map, *m_K, m_loops, m_cfg.refinement, m_cfg.mapping, m_cfg.sensor == Sensor::Monocular);
		m_finalScaleUndone = ba.undoneScale;
		// Metres again on the adjusted map (its scale was held, not measured).
		if (m_metricScale)
		{
			std::lock_guard<std::mutex> lock(m_map.mutex());
			if (const auto r = m_metricScale->finalEstimate(m_map)) followWholeMapRescale(r->factor, nullptr);
		}
		m_globalBa = ba.report;
		window = std::move(ba.window);
	}
	m_timings.add("global_bundle_adjustment", secondsSince(t0));
	return window;
}

std::map<std::string, double> System::reanchorMaps(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before)
{
	std::map<std::string, double> seconds;
	if (!m_maps || m_localizeOnly) return seconds;
	const auto& rc = m_cfg.refinement;
	// Re-anchor the maps on the refined keyframe poses, unless no keyframe moved enough to
	// show in them (a grid rebuild costs as much as the whole map).
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> poses;
	for (const auto& [id, T0] : before)
	{
		mrpt::poses::CPose3D T;
		if (m_map.poseOf(id, T)) poses[id] = T;
	}
	FinalMapShift shift;
	shift.largest = largestDisplacement(before, poses, rc.mapReanchorDepth);
	// Keyframes without depth hold triangulated points, which the refinement moved against
	// their keyframes too: the maps take them as refined (and rebuild for them).
	const auto refreshed = m_maps->refreshedMapPoints(m_map);
	shift.reanchored = shift.largest > rc.mapReanchorMinShift || !refreshed.empty();
	m_finalMapShift = shift;
	if (shift.reanchored) seconds = publishCorrection({PoseCorrection::Source::FinalRefinement, poses, 0, nullptr, &refreshed}, nullptr);
	m_maps->syncLandmarks(m_map, m_cfg.tracker.hoc);
	return seconds;
}

void System::refineFrames(const std::optional<std::set<sfm::KeyFrameId>>& window)
{
	if (!m_cfg.refinement.refineFrames) return;
	const auto t0 = std::chrono::steady_clock::now();
	const sfm::SparseMap& map = m_map;
	auto pose = m_cfg.tracker.pose;
	pose.rounds = m_cfg.refinement.framePoseRounds;
	m_refined = refineFramePoses(
		m_frames, trajectory(), m_map, *m_K, pose, m_cfg.tracker.minInliers,
		[&](const sfm::TrackedFrame& f)
		{
			// A keyframe keeps its pose from the (global) bundle adjustment: that joint estimate
			// beats a pose-only one against points it helped place (measured in doc/evaluation-history.md).
			if (f.newKeyFrame && map.hasKeyFrame(f.keyframe)) return false;
			// Bounded: only frames whose reference keyframe the refinement moved; the others
			// follow their reference keyframe (trajectory()).
			return !window || (f.hasReference && window->count(f.reference) > 0);
		});
	m_timings.add("frame_refinement", secondsSince(t0));
}

void System::storeFinalSession()
{
	const auto t0 = std::chrono::steady_clock::now();
	try
	{
		noteRunAttributes();
		m_recorder->finish(m_map, m_loopCloser.get(), m_maps.get());
	}
	catch (const std::exception& e)
	{
		// The other outputs are still written; the error is reported with them.
		std::lock_guard<std::mutex> lk(m_statsMutex);
		if (m_backgroundError.empty()) m_backgroundError = std::string("session store: ") + e.what();
	}
	m_timings.add("session_store", secondsSince(t0));
}

core::Trajectory System::trajectory() const
{
	core::Trajectory out;
	out.reserve(m_frames.size());
	for (std::size_t i = 0; i < m_frames.size(); i++)
	{
		const auto& f = m_frames[i];
		if (i < m_refined.size() && m_refined[i])
		{
			out.push_back({f.timestamp, *m_refined[i]});
			continue;
		}
		mrpt::poses::CPose3D T_world_ref;
		if (f.hasReference && m_map.poseOf(f.reference, T_world_ref))
			out.push_back({f.timestamp, T_world_ref + f.T_ref_cam});
		else
			out.push_back({f.timestamp, f.T_world_cam});
	}
	return out;
}

core::Trajectory System::keyframeTrajectory() const
{
	core::Trajectory out;
	for (const auto& [id, kf] : m_map.keyframes()) out.push_back({kf.timestamp, kf.T_world_cam});
	return out;
}

}  // namespace keygrid::slam

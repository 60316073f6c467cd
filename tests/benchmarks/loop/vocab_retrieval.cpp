/** \file vocab_retrieval.cpp
 * Which vocabulary works on real data with nothing downloaded? Place retrieval on TUM fr1_rpy
 * (250 frames, ../shared/data) with vocabularies trained on:
 *   self      - the sequence's own 250 frames (a pre-pass over the input),
 *   self/10   - every 10th frame of the sequence (a quick pre-pass),
 *   procedural- 100 views of a generated texture (shapes), nothing real,
 *   other     - the other real frames we have (fr1_desk 9 + ICL living room 5),
 *   self/5 L3, self/5 L4 - every 5th frame (keygrid-vocab train --every 5), k = 10, depth 3 / 4,
 *   first10 L3 - frames 0, 5, ..., 45 with k = 10, L = 3 (like keygrid-slam's in-run training),
 *   NAME=FILE - vocabularies given on the command line (e.g. the shipped default).
 * Database: frames 0, 10, 20, ...; queries: frames 5, 15, 25, ... A database frame shows the same
 * place as the query when (ground truth) their optical axes differ by < 15 deg and centres by
 * < 0.3 m. "revisit" ignores database frames within 1 s of the query, so only returns to an
 * earlier view count. Prints recall@1 (top candidate is a same-place frame) per vocabulary and,
 * over the revisit queries, the median of (best same-place score / best other-place score).
 * Run: <build>/bin/keygrid_vocab_retrieval [SHARED_DATA_DIR] [NAME=FILE.bin ...]
 */
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/loop/KeyFrameDatabase.h>
#include <keygrid/loop/Vocabulary.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <random>

using namespace keygrid;

namespace
{
struct Seq
{
	std::vector<cv::Mat> desc;
	std::vector<double> t;
	std::vector<mrpt::poses::CPose3D> pose;  //!< ground truth (when known)
};

Seq readSequence(const std::string& dir, bool withGt)
{
	Seq s;
	auto src = core::openFrameSource(dir);
	auto orb = cv::ORB::create(1000);
	core::Trajectory gt;
	if (withGt) gt = core::readTumTrajectory(dir + "/groundtruth.txt");
	core::Frame f;
	while (src->next(f))
	{
		std::vector<cv::KeyPoint> kps;
		cv::Mat d;
		orb->detectAndCompute(f.grey, cv::noArray(), kps, d);
		s.desc.push_back(d);
		s.t.push_back(f.timestamp);
		if (withGt)
		{
			const auto it = std::min_element(gt.begin(), gt.end(), [&](const auto& a, const auto& b) {
				return std::abs(a.t - f.timestamp) < std::abs(b.t - f.timestamp);
			});
			s.pose.push_back(it->T_world_cam);
		}
	}
	return s;
}

std::vector<cv::Mat> proceduralViews(int count)
{
	std::mt19937_64 rng(1);
	const int W = 3000, H = 2000;
	std::uniform_int_distribution<int> x(0, W - 1), y(0, H - 1), r(3, 40), g(0, 255);
	cv::Mat world(H, W, CV_8U, cv::Scalar(128));
	for (int i = 0; i < 30000; ++i)
	{
		if (i % 3 == 0) cv::rectangle(world, cv::Rect(x(rng), y(rng), r(rng), r(rng)), cv::Scalar(g(rng)), cv::FILLED);
		else if (i % 3 == 1) cv::circle(world, cv::Point(x(rng), y(rng)), r(rng), cv::Scalar(g(rng)), cv::FILLED);
		else cv::line(world, cv::Point(x(rng), y(rng)), cv::Point(x(rng), y(rng)), cv::Scalar(g(rng)), 2);
	}
	cv::GaussianBlur(world, world, cv::Size(3, 3), 0.8);
	auto orb = cv::ORB::create(1000);
	std::uniform_int_distribution<int> vx(0, W - 640), vy(0, H - 480);
	std::vector<cv::Mat> out;
	for (int i = 0; i < count; ++i)
	{
		std::vector<cv::KeyPoint> kps;
		cv::Mat d;
		orb->detectAndCompute(world(cv::Rect(vx(rng), vy(rng), 640, 480)), cv::noArray(), kps, d);
		out.push_back(d);
	}
	return out;
}

bool samePlace(const mrpt::poses::CPose3D& a, const mrpt::poses::CPose3D& b)
{
	const auto Ra = a.getRotationMatrix(), Rb = b.getRotationMatrix();
	double dot = 0;
	for (int i = 0; i < 3; ++i) dot += Ra(i, 2) * Rb(i, 2);
	const double angle = std::acos(std::clamp(dot, -1.0, 1.0)) * 180.0 / M_PI;
	return angle < 15.0 && a.distanceTo(b) < 0.3;
}

void evaluate(const std::string& name, const loop::Vocabulary& v, const Seq& s, double trainSeconds)
{
	loop::KeyFrameDatabase db;
	std::vector<loop::BowVector> bows;
	for (const auto& d : s.desc) bows.push_back(v.transform(d));
	for (std::size_t i = 0; i < s.desc.size(); i += 10) db.add(i, bows[i]);
	int queries = 0, correct = 0, revisitQueries = 0, revisitCorrect = 0;
	std::vector<double> margins;
	for (std::size_t q = 5; q < s.desc.size(); q += 10)
	{
		bool any = false, anyFar = false;
		loop::DatabaseQuery opt;
		opt.maxResults = 1;
		for (std::size_t d = 0; d < s.desc.size(); d += 10)
		{
			const bool same = samePlace(s.pose[q], s.pose[d]);
			const bool near = std::abs(s.t[q] - s.t[d]) < 1.0;
			any |= same;
			anyFar |= same && !near;
			if (near) opt.exclude.insert(d);
		}
		if (any)
		{
			++queries;
			const auto r = db.query(bows[q], loop::DatabaseQuery{1, 0.0, 0.0, 1.0, 0.8, {}});
			correct += !r.empty() && samePlace(s.pose[q], s.pose[r[0].id]);
		}
		if (anyFar)
		{
			++revisitQueries;
			const auto r = db.query(bows[q], opt);
			revisitCorrect += !r.empty() && samePlace(s.pose[q], s.pose[r[0].id]);
			// Margin: best same-place score over best other-place score (> 1: separable).
			double same = 0, other = 0;
			for (std::size_t d = 0; d < s.desc.size(); d += 10)
			{
				if (opt.exclude.count(d)) continue;
				double& best = samePlace(s.pose[q], s.pose[d]) ? same : other;
				best = std::max(best, v.score(bows[q], bows[d]));
			}
			margins.push_back(same / std::max(other, 1e-9));
		}
	}
	std::sort(margins.begin(), margins.end());
	const double medianMargin = margins.empty() ? 0.0 : margins[margins.size() / 2];
	std::printf(
		"| %-10s | %6zu | %5zu | %5.1f | %2d/%2d (%3.0f %%) | %2d/%2d (%3.0f %%) | %5.2f |\n", name.c_str(), v.trainingImages(),
		v.numWords(), trainSeconds, correct, queries, 100.0 * correct / std::max(1, queries), revisitCorrect, revisitQueries,
		100.0 * revisitCorrect / std::max(1, revisitQueries), medianMargin);
}

loop::Vocabulary timedTrain(const std::vector<cv::Mat>& d, double& seconds, int levels = 4)
{
	const auto t0 = std::chrono::steady_clock::now();
	loop::VocabularyOptions o;  // k = 10, L = 4 unless told
	o.levels = levels;
	auto v = loop::Vocabulary::train(d, o);
	seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	return v;
}
}  // namespace

int main(int argc, char** argv)
{
	const std::string data = argc > 1 && std::string(argv[1]).find('=') == std::string::npos ? argv[1] : KEYGRID_SHARED_DATA_DIR;
	const std::string rpy = data + "/tum_fr1_rpy_first250";
	if (!std::filesystem::is_directory(rpy))
	{
		std::cerr << "keygrid_vocab_retrieval: " << rpy << " not found\n";
		return 1;
	}
	const Seq s = readSequence(rpy, true);
	std::vector<cv::Mat> other = readSequence(data + "/tum_fr1_desk_9frames", false).desc;
	for (const auto& d : readSequence(data + "/icl_nuim_livingroom_5frames", false).desc) other.push_back(d);
	std::vector<cv::Mat> sub;
	for (std::size_t i = 0; i < s.desc.size(); i += 10) sub.push_back(s.desc[i]);

	std::printf("fr1_rpy: %zu frames, database every 10th, queries at +5\n", s.desc.size());
	std::printf("| vocabulary | images | words | train [s] | recall@1 | revisit recall@1 | median margin |\n|---|---|---|---|---|---|---|\n");
	double sec = 0;
	{
		const auto v = timedTrain(s.desc, sec);
		evaluate("self", v, s, sec);
	}
	{
		const auto v = timedTrain(sub, sec);
		evaluate("self/10", v, s, sec);
	}
	{
		const auto v = timedTrain(proceduralViews(100), sec);
		evaluate("procedural", v, s, sec);
	}
	{
		const auto v = timedTrain(other, sec);
		evaluate("other", v, s, sec);
	}
	std::vector<cv::Mat> sub5;
	for (std::size_t i = 0; i < s.desc.size(); i += 5) sub5.push_back(s.desc[i]);
	for (int levels : {3, 4})
	{
		const auto v = timedTrain(sub5, sec, levels);
		evaluate("self/5 L" + std::to_string(levels), v, s, sec);
	}
	{
		// What keygrid-slam's in-run default sees: 10 early frames (keyframes come every few
		// frames), k = 10, L = 3.
		std::vector<cv::Mat> first(sub5.begin(), sub5.begin() + std::min<std::size_t>(10, sub5.size()));
		const auto v = timedTrain(first, sec, 3);
		evaluate("first10 L3", v, s, sec);
	}
	for (int i = 1; i < argc; ++i)
	{
		const std::string a = argv[i];
		const auto eq = a.find('=');
		if (eq == std::string::npos) continue;
		evaluate(a.substr(0, eq), loop::Vocabulary::load(a.substr(eq + 1)), s, 0.0);
	}
	return 0;
}

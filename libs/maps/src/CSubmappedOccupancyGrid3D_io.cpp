#include <keygrid/core/AtomicOutput.h>
/** \file CSubmappedOccupancyGrid3D_io.cpp
 * Versioned serialization, OctoMap .bt and PLY exports, 3D visualization.
 */
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/maps/OctomapBinaryWriter.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

using namespace keygrid;

namespace
{
using mrpt::serialization::CArchive;

void writePose(CArchive& out, const mrpt::poses::CPose3D& T)
{
	mrpt::math::CMatrixDouble44 H;
	T.getHomogeneousMatrix(H);
	for (int r = 0; r < 3; ++r)
		for (int c = 0; c < 4; ++c) out << H(r, c);
}
mrpt::poses::CPose3D readPose(CArchive& in)
{
	mrpt::math::CMatrixDouble44 H = mrpt::math::CMatrixDouble44::Identity();
	for (int r = 0; r < 3; ++r)
		for (int c = 0; c < 4; ++c) in >> H(r, c);
	return mrpt::poses::CPose3D(H);
}

void writeCamera(CArchive& out, const core::RgbdCamera& c)
{
	out << c.name << uint32_t(c.width) << uint32_t(c.height) << c.fx << c.fy << c.cx << c.cy;
	for (double d : c.dist) out << d;
	out << c.depthUnits;
}
core::RgbdCamera readCamera(CArchive& in)
{
	core::RgbdCamera c;
	uint32_t w = 0, h = 0;
	in >> c.name >> w >> h >> c.fx >> c.fy >> c.cx >> c.cy;
	for (double& d : c.dist) in >> d;
	in >> c.depthUnits;
	c.width = w;
	c.height = h;
	return c;
}

void writeGrid(CArchive& out, const VoxelBlockGrid& g)
{
	std::vector<std::pair<VoxelIndex, const VoxelBlock*>> blocks;
	for (const auto& [b, blk] : g.blocks()) blocks.emplace_back(b, blk.get());
	std::sort(blocks.begin(), blocks.end(),
		[](const auto& a, const auto& b) { return a.first < b.first; });
	out << g.resolution() << uint64_t(blocks.size());
	std::vector<float> buf(2 * VoxelBlock::kVoxels);
	for (const auto& [b, blk] : blocks)
	{
		out << b.x << b.y << b.z;
		for (int i = 0; i < VoxelBlock::kVoxels; ++i)
		{
			buf[i] = blk->voxels[i].logOdds;
			buf[VoxelBlock::kVoxels + i] = blk->voxels[i].travelled;
		}
		out.WriteBufferFixEndianness(buf.data(), buf.size());
	}
}
void readGrid(CArchive& in, VoxelBlockGrid& g)
{
	double res = 0;
	uint64_t n = 0;
	in >> res >> n;
	g.reset(res);
	std::vector<float> buf(2 * VoxelBlock::kVoxels);
	for (uint64_t k = 0; k < n; ++k)
	{
		VoxelIndex b;
		in >> b.x >> b.y >> b.z;
		in.ReadBufferFixEndianness(buf.data(), buf.size());
		VoxelBlock& blk = g.blockAt(b);
		for (int i = 0; i < VoxelBlock::kVoxels; ++i)
		{
			blk.voxels[i].logOdds = buf[i];
			blk.voxels[i].travelled = buf[VoxelBlock::kVoxels + i];
		}
	}
}
}  // namespace

// Version 1 adds morphingOptions.interpolation after morphingOptions.threads;
// version-0 archives load with Nearest, the behaviour they were written with.
// Version 2 adds morphingOptions.maxKeyframesPerBlock after it (older: 0 = all).
// Version 3 adds, per keyframe after its depth, whether it was integrated from map points and
// those points (camera frame). Written only by a grid holding such a keyframe, so a grid of
// depth keyframes keeps the version-2 archive it always had.
uint8_t CSubmappedOccupancyGrid3D::serializeGetVersion() const
{
	for (const auto& [id, k] : m_keyframes)
		if (k.fromMapPoints) return 3;
	return 2;
}

void CSubmappedOccupancyGrid3D::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << m_resolution;
	// Options, field by field (binary: exact round trip).
	const auto& io = insertionOptions.integration;
	out << io.maxRange << io.minRange << uint32_t(io.pixelDecimation) << uint32_t(io.threads)
		<< io.logOddsHit << io.logOddsMiss << io.logOddsMin << io.logOddsMax
		<< io.maxDenseMarkVoxels << io.discretizeEndpoints;
	const auto& co = insertionOptions.conflict;
	out << co.travelledDistanceThreshold << co.occupiedConfidentLogOdds << co.freeConfidentLogOdds
		<< co.conflictMinVoxels << co.conflictMinFraction << co.localizationEnterHitFraction
		<< co.localizationExitHitFraction << co.localizationMaxContradictionFraction;
	out << insertionOptions.storeKeyframeDepth << insertionOptions.observationsAreKeyframes;
	out << morphingOptions.viewConeMaxRange << morphingOptions.travelWindow
		<< morphingOptions.weightExponent
		<< morphingOptions.minWeightDistance << morphingOptions.keepVoxelsOutsideCones
		<< uint32_t(morphingOptions.threads) << uint8_t(morphingOptions.interpolation)
		<< uint32_t(morphingOptions.maxKeyframesPerBlock);
	out << uint32_t(likelihoodOptions.decimation) << likelihoodOptions.maxRange
		<< likelihoodOptions.minProbability;
	// State.
	out << uint8_t(m_modeMachine.mode()) << m_modeMachine.revisitPending() << uint64_t(m_active)
		<< m_lastKeyframe.has_value() << m_lastKeyframe.value_or(0) << m_obsTravelled
		<< m_nextObsKeyframeId << m_lastObsCamPose.has_value();
	if (m_lastObsCamPose) writePose(out, *m_lastObsCamPose);
	// Submaps.
	out << uint64_t(m_submaps.size());
	for (const auto& s : m_submaps)
	{
		out << s.anchorKeyframe << s.keyframes;
		writeGrid(out, s.grid);
	}
	// Keyframes.
	const bool withMapPoints = serializeGetVersion() >= 3;
	out << uint64_t(m_keyframes.size());
	for (const auto& [id, k] : m_keyframes)
	{
		out << id << k.travelled << uint64_t(k.submap);
		writePose(out, k.T_world_cam);
		writeCamera(out, k.camera);
		const bool hasDepth = !k.depth.empty();
		out << hasDepth;
		if (hasDepth)
		{
			const cv::Mat d = k.depth.isContinuous() ? k.depth : k.depth.clone();
			out << int32_t(d.rows) << int32_t(d.cols);
			out.WriteBufferFixEndianness(d.ptr<float>(), d.total());
		}
		if (withMapPoints)
		{
			out << k.fromMapPoints << uint64_t(k.points_cam.size());
			for (const auto& p : k.points_cam) out << p.x << p.y << p.z;
		}
	}
}

void CSubmappedOccupancyGrid3D::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		case 1:
		case 2:
		case 3:
		{
			in >> m_resolution;
			auto& io = insertionOptions.integration;
			uint32_t u1 = 0, u2 = 0;
			in >> io.maxRange >> io.minRange >> u1 >> u2 >> io.logOddsHit >> io.logOddsMiss >>
				io.logOddsMin >> io.logOddsMax >> io.maxDenseMarkVoxels >> io.discretizeEndpoints;
			io.pixelDecimation = u1;
			io.threads = u2;
			auto& co = insertionOptions.conflict;
			in >> co.travelledDistanceThreshold >> co.occupiedConfidentLogOdds >>
				co.freeConfidentLogOdds >> co.conflictMinVoxels >> co.conflictMinFraction >>
				co.localizationEnterHitFraction >> co.localizationExitHitFraction >>
				co.localizationMaxContradictionFraction;
			in >> insertionOptions.storeKeyframeDepth >> insertionOptions.observationsAreKeyframes;
			in >> morphingOptions.viewConeMaxRange >> morphingOptions.travelWindow >>
				morphingOptions.weightExponent >>
				morphingOptions.minWeightDistance >> morphingOptions.keepVoxelsOutsideCones >> u1;
			morphingOptions.threads = u1;
			morphingOptions.interpolation = MorphingOptions::Interpolation::Nearest;
			if (version >= 1)
			{
				uint8_t interp = 0;
				in >> interp;
				if (interp > 1) throw std::runtime_error("CSubmappedOccupancyGrid3D: bad morphing interpolation " + std::to_string(interp));
				morphingOptions.interpolation = static_cast<MorphingOptions::Interpolation>(interp);
			}
			morphingOptions.maxKeyframesPerBlock = 0;
			if (version >= 2)
			{
				in >> u1;
				morphingOptions.maxKeyframesPerBlock = u1;
			}
			in >> u1 >> likelihoodOptions.maxRange >> likelihoodOptions.minProbability;
			likelihoodOptions.decimation = u1;

			uint8_t mode = 0;
			bool pending = false, hasLastKf = false, hasLastPose = false;
			uint64_t active = 0, lastKf = 0;
			in >> mode >> pending >> active >> hasLastKf >> lastKf >> m_obsTravelled >>
				m_nextObsKeyframeId >> hasLastPose;
			if (mode > 1) throw std::runtime_error("CSubmappedOccupancyGrid3D: bad mode in stream");
			m_modeMachine = MappingModeMachine(insertionOptions.conflict);
			m_modeMachine.setMode(static_cast<MappingMode>(mode));
			if (pending) m_modeMachine.notifyRevisit();
			m_lastKeyframe = hasLastKf ? std::optional<uint64_t>(lastKf) : std::nullopt;
			m_lastObsCamPose.reset();
			if (hasLastPose) m_lastObsCamPose = readPose(in);

			uint64_t ns = 0;
			in >> ns;
			m_submaps.clear();
			for (uint64_t i = 0; i < ns; ++i)
			{
				Submap s(m_resolution);
				in >> s.anchorKeyframe >> s.keyframes;
				readGrid(in, s.grid);
				m_submaps.push_back(std::move(s));
			}
			if (m_submaps.empty() || active >= m_submaps.size())
				throw std::runtime_error("CSubmappedOccupancyGrid3D: bad submap index in stream");
			m_active = static_cast<std::size_t>(active);

			uint64_t nk = 0;
			in >> nk;
			m_keyframes.clear();
			for (uint64_t i = 0; i < nk; ++i)
			{
				KeyframeRecord k;
				uint64_t sub = 0;
				in >> k.id >> k.travelled >> sub;
				k.submap = static_cast<std::size_t>(sub);
				k.T_world_cam = readPose(in);
				k.camera = readCamera(in);
				bool hasDepth = false;
				in >> hasDepth;
				if (hasDepth)
				{
					int32_t rows = 0, cols = 0;
					in >> rows >> cols;
					k.depth.create(rows, cols, CV_32FC1);
					in.ReadBufferFixEndianness(k.depth.ptr<float>(), k.depth.total());
				}
				if (version >= 3)
				{
					uint64_t np = 0;
					in >> k.fromMapPoints >> np;
					k.points_cam.resize(np);
					for (auto& p : k.points_cam) in >> p.x >> p.y >> p.z;
				}
				m_keyframes.emplace(k.id, std::move(k));
			}
			m_integrator.ptr.reset();
		}
		break;
		default:
			MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

// ---------------------------------------------------------------- exports
namespace
{
/** Calls f(outIndex, voxel) for every voxel of an output lattice (same resolution, frame
 * T_out_world) whose centre lies in a known voxel of g, with that voxel (nearest-neighbour
 * resampling). A centre lies in exactly one world voxel, and that voxel's own centre maps to
 * within half a voxel diagonal of it, i.e. into one of the 27 output voxels around the
 * voxel holding the mapped centre: those 27 are tested per known world voxel. */
template <class F>
void forEachResampled(const VoxelBlockGrid& g, const mrpt::poses::CPose3D& T_out_world, F&& f)
{
	const mrpt::poses::CPose3D T_world_out = -T_out_world;
	g.forEachKnown([&](const VoxelIndex& vi, const Voxel& v) {
		const VoxelIndex k = g.voxelOf(T_out_world.composePoint(g.centreOf(vi)));
		for (int dz = -1; dz <= 1; ++dz)
			for (int dy = -1; dy <= 1; ++dy)
				for (int dx = -1; dx <= 1; ++dx)
				{
					const VoxelIndex o{k.x + dx, k.y + dy, k.z + dz};
					if (g.voxelOf(T_world_out.composePoint(g.centreOf(o))) == vi) f(o, v);
				}
	});
}
}  // namespace

void CSubmappedOccupancyGrid3D::saveAsOctomapBinary(const std::string& path, const maps::ExportFrame& frame) const
{
	maps::OctomapBinaryWriter bt;
	std::size_t outside = 0;
	{
		const VoxelBlockGrid g = fusedGrid();
		// OctoMap calls log-odds >= 0 occupied, keygrid > 0: p = 0.5 stays free.
		auto put = [&](const VoxelIndex& vi, const Voxel& v) {
			if (!bt.add(vi.x, vi.y, vi.z, v.logOdds > 0.0f)) ++outside;
		};
		if (frame.isIdentity())
			g.forEachKnown(put);
		else
			forEachResampled(g, frame.T_out_world, put);
	}
	if (outside > 0)
		throw std::runtime_error(
			"saveAsOctomapBinary: " + std::to_string(outside) +
			" voxels lie outside the OcTree key range (+-32768 voxels)");
	// The frame goes in as a comment line of the header, which OctoMap's reader skips.
	core::writeFileAtomically(path, [&](std::ostream& f) { bt.write(f, m_resolution, frame.comment); });
}

void CSubmappedOccupancyGrid3D::saveOccupiedAsPly(const std::string& path, const maps::ExportFrame& frame) const
{
	auto pts = occupiedVoxelCentres();
	if (!frame.isIdentity())
		for (auto& p : pts) p = frame.T_out_world.composePoint(p);
	core::writeFileAtomically(path, [&](std::ostream& f) {
		f << "ply\nformat ascii 1.0\ncomment keygrid CSubmappedOccupancyGrid3D occupied voxel "
			 "centres, resolution "
		  << m_resolution << " m\n";
		if (!frame.comment.empty()) f << "comment " << frame.comment << "\n";
		f << "element vertex " << pts.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
		for (const auto& p : pts) f << float(p.x) << ' ' << float(p.y) << ' ' << float(p.z) << '\n';
	});
}

void CSubmappedOccupancyGrid3D::saveMetricMapRepresentationToFile(const std::string& prefix) const
{
	saveAsOctomapBinary(prefix + ".bt");
	saveOccupiedAsPly(prefix + "_occupied.ply");
	saveAs3DScene(prefix + ".3Dscene");
}

void CSubmappedOccupancyGrid3D::saveAs3DScene(const std::string& path) const
{
	mrpt::opengl::COpenGLScene scene;
	auto objs = mrpt::opengl::CSetOfObjects::Create();
	getVisualizationInto(*objs);
	scene.insert(objs);
	core::saveGzAtomically(scene, path);  // what COpenGLScene::saveToFile writes, with the close checked
}

void CSubmappedOccupancyGrid3D::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const
{
	if (!genericMapParams.enableSaveAs3DObject) return;
	auto pc = mrpt::opengl::CPointCloud::Create();
	for (const auto& p : occupiedVoxelCentres())
		pc->insertPoint(float(p.x), float(p.y), float(p.z));
	pc->setPointSize(3.0f);
	pc->enableColorFromZ(true);
	pc->setName("keygrid::CSubmappedOccupancyGrid3D occupied voxels");
	outObj.insert(pc);
}

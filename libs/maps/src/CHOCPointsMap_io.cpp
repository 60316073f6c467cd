#include <keygrid/core/AtomicOutput.h>
/** \file CHOCPointsMap_io.cpp
 * CHOCPointsMap: versioned serialization (options, points, descriptors, histograms), PLY export
 * and SceneViewer3D visualization.
 */
#include <keygrid/maps/CHOCPointsMap.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <stdexcept>

using namespace keygrid;

namespace
{
/** Largest bin weight -> colour: red (0) through yellow to green (1). */
mrpt::img::TColorf weightColour(double w)
{
	w = std::clamp(w, 0.0, 1.0);
	return {static_cast<float>(std::min(1.0, 2 * (1 - w))), static_cast<float>(std::min(1.0, 2 * w)), 0.f};
}
int positiveObservations(const maps::HocHistogram& h)
{
	int s = 0;
	for (auto n : h.counts()) s += std::max<int>(0, n);
	return s;
}
}  // namespace

// Version 1 adds HocOptions::decrementNeedsKeypoint after the other options; version 0 streams
// read it as false (the behaviour they were written with).
uint8_t CHOCPointsMap::serializeGetVersion() const { return 1; }

void CHOCPointsMap::serializeTo(mrpt::serialization::CArchive& out) const
{
	const auto& o = hocOptions;
	out << o.enabled << uint32_t(o.radii.size());
	for (double r : o.radii) out << r;
	out << int32_t(o.subdivisions) << o.sigmoidGain << o.sigmoidOffset << o.selectThreshold << o.pruneThreshold
		<< int32_t(o.countLimit) << int32_t(o.initialCount) << o.occlusionToleranceAbs << o.occlusionToleranceRel << o.visibleDepthMin << o.visibleDepthMax;
	out << o.decrementNeedsKeypoint;
	out << int32_t(insertionOptions.decimation) << insertionOptions.pointSpacing << insertionOptions.prune;
	out << int32_t(likelihoodOptions.decimation) << likelihoodOptions.sigma << likelihoodOptions.outlierProbability;
	out << m_nextId << uint64_t(m_points.size());
	for (const auto& p : m_points)
	{
		out << p.id << p.p.x << p.p.y << p.p.z;
		out << uint32_t(p.descriptor.size());
		if (!p.descriptor.empty()) out.WriteBuffer(p.descriptor.data(), p.descriptor.size());
		const auto& n = p.hoc.counts();
		out << uint32_t(n.size());
		if (!n.empty()) out.WriteBufferFixEndianness(n.data(), n.size());
	}
}

void CHOCPointsMap::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	if (version > 1) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	maps::HocOptions o;
	uint32_t nr = 0;
	in >> o.enabled >> nr;
	if (nr == 0 || nr > 64) throw std::runtime_error("CHOCPointsMap: corrupt stream (" + std::to_string(nr) + " shells)");
	o.radii.resize(nr);
	for (auto& r : o.radii) in >> r;
	int32_t sub = 0, lim = 0, init = 0, idec = 0, ldec = 0;
	in >> sub >> o.sigmoidGain >> o.sigmoidOffset >> o.selectThreshold >> o.pruneThreshold >> lim >> init >> o.occlusionToleranceAbs >>
		o.occlusionToleranceRel >> o.visibleDepthMin >> o.visibleDepthMax;
	if (version >= 1) in >> o.decrementNeedsKeypoint;
	else o.decrementNeedsKeypoint = false;  // the default changed to true after version 0
	o.subdivisions = sub;
	o.countLimit = lim;
	o.initialCount = init;
	o.validate();
	TInsertionOptions io;
	TLikelihoodOptions lo;
	in >> idec >> io.pointSpacing >> io.prune >> ldec >> lo.sigma >> lo.outlierProbability;
	io.decimation = idec;
	lo.decimation = ldec;
	hocOptions = o;
	insertionOptions = io;
	likelihoodOptions = lo;
	const auto nb = static_cast<uint32_t>(geometry().numBins());
	uint64_t n = 0;
	in >> m_nextId >> n;
	m_points.clear();
	m_points.reserve(static_cast<std::size_t>(std::min<uint64_t>(n, 1u << 20)));
	for (uint64_t i = 0; i < n; i++)
	{
		Point p;
		uint32_t nd = 0, nbins = 0;
		in >> p.id >> p.p.x >> p.p.y >> p.p.z >> nd;
		if (nd > 4096) throw std::runtime_error("CHOCPointsMap: corrupt stream (descriptor of " + std::to_string(nd) + " bytes)");
		p.descriptor.resize(nd);
		if (nd) in.ReadBuffer(p.descriptor.data(), nd);
		in >> nbins;
		if (nbins != 0 && nbins != nb)
			throw std::runtime_error("CHOCPointsMap: corrupt stream (" + std::to_string(nbins) + " bins, expected " + std::to_string(nb) + ")");
		std::vector<int16_t> counts(nbins);
		if (nbins) in.ReadBufferFixEndianness(counts.data(), nbins);
		p.hoc.setCounts(std::move(counts));
		m_points.push_back(std::move(p));
	}
}

void CHOCPointsMap::saveAsPly(const std::string& path, const maps::ExportFrame& frame) const
{
	core::writeFileAtomically(path, [&](std::ostream& f) {
		f << "ply\nformat ascii 1.0\ncomment keygrid CHOCPointsMap: colour and weight = largest HOC bin weight\n";
		if (!frame.comment.empty()) f << "comment " << frame.comment << "\n";
		const bool move = !frame.isIdentity();
		f << "element vertex " << m_points.size() << "\n";
		f << "property float x\nproperty float y\nproperty float z\n";
		f << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
		f << "property float weight\nproperty int observations\nend_header\n";
		char line[200];
		for (std::size_t i = 0; i < m_points.size(); i++)
		{
			const auto& p = m_points[i];
			const double w = maxWeight(i);
			const auto c = weightColour(w);
			const auto q = move ? frame.T_out_world.composePoint(p.p) : p.p;
			std::snprintf(line, sizeof(line), "%.5f %.5f %.5f %d %d %d %.4f %d\n", q.x, q.y, q.z, static_cast<int>(255 * c.R),
						  static_cast<int>(255 * c.G), static_cast<int>(255 * c.B), w, positiveObservations(p.hoc));
			f << line;
		}
	});
}

void CHOCPointsMap::saveMetricMapRepresentationToFile(const std::string& prefix) const { saveAsPly(prefix + ".ply"); }

void CHOCPointsMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const
{
	auto cloud = mrpt::opengl::CPointCloudColoured::Create();
	cloud->setPointSize(renderOptions.pointSize);
	cloud->setName("hoc_points");
	for (std::size_t i = 0; i < m_points.size(); i++)
	{
		const auto& p = m_points[i].p;
		const auto c = weightColour(maxWeight(i));
		cloud->push_back(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), c.R, c.G, c.B);
	}
	outObj.insert(cloud);
	if (renderOptions.glyphs <= 0 || m_points.empty()) return;

	// Glyphs: the innermost shell's faces around the most observed points, each face coloured
	// by the weight of that face's bin summed over shells (the largest n of the shells).
	std::vector<std::size_t> order(m_points.size());
	std::iota(order.begin(), order.end(), 0);
	const std::size_t n = std::min<std::size_t>(order.size(), static_cast<std::size_t>(renderOptions.glyphs));
	std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), order.end(), [&](std::size_t a, std::size_t b) {
		return positiveObservations(m_points[a].hoc) > positiveObservations(m_points[b].hoc);
	});
	const auto& g = geometry();
	auto glyphs = mrpt::opengl::CSetOfTriangles::Create();
	glyphs->setName("hoc_glyphs");
	for (std::size_t k = 0; k < n; k++)
	{
		const auto& pt = m_points[order[k]];
		for (int f = 0; f < g.numFaces(); f++)
		{
			int best = -30000;
			for (int s = 0; s < g.numShells(); s++) best = std::max(best, pt.hoc.count(s * g.numFaces() + f));
			const auto c = weightColour(hocOptions.weight(best));
			const auto v = g.faceVertices(f);
			mrpt::opengl::TTriangle t;
			for (int j = 0; j < 3; j++)
			{
				t.vertex(j) = {static_cast<float>(pt.p.x + renderOptions.glyphRadius * v[j].x()), static_cast<float>(pt.p.y + renderOptions.glyphRadius * v[j].y()),
							   static_cast<float>(pt.p.z + renderOptions.glyphRadius * v[j].z())};
				t.r(j) = static_cast<uint8_t>(255 * c.R);
				t.g(j) = static_cast<uint8_t>(255 * c.G);
				t.b(j) = static_cast<uint8_t>(255 * c.B);
				t.a(j) = 200;
			}
			t.computeNormals();
			glyphs->insertTriangle(t);
		}
	}
	outObj.insert(glyphs);
}

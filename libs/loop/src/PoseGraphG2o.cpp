#include <keygrid/core/AtomicOutput.h>
/** \file PoseGraphG2o.cpp
 * g2o text export/import of the pose graph (VERTEX_SE3:QUAT / EDGE_SE3:QUAT / FIX). */
#include <keygrid/loop/PoseGraph.h>

#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace keygrid::loop
{
namespace
{
void writePose(std::ostream& os, const Eigen::Isometry3d& T)
{
	const Eigen::Quaterniond q(T.linear());
	const Eigen::Vector3d t = T.translation();
	os << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w();
}

Eigen::Isometry3d readPose(std::istream& is)
{
	double x, y, z, qx, qy, qz, qw;
	if (!(is >> x >> y >> z >> qx >> qy >> qz >> qw)) throw std::runtime_error("expected x y z qx qy qz qw");
	const Eigen::Quaterniond q(qw, qx, qy, qz);
	if (!(q.norm() > 1e-9)) throw std::runtime_error("zero quaternion");
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = q.normalized().toRotationMatrix();
	T.translation() = Eigen::Vector3d(x, y, z);
	return T;
}
}  // namespace

void PoseGraph::writeG2o(const std::string& path) const
{
	core::writeFileAtomically(path, [&](std::ostream& f) {
		f << std::setprecision(17);
		f << "# keygrid pose graph: VERTEX_SE3:QUAT id x y z qx qy qz qw (T_world_kf); EDGE_SE3:QUAT a b T_a_b\n"
		  << "# + 21 upper-triangular information entries, order x y z rx ry rz (rotation error 2 vec(dq))\n";
		for (const auto& [id, T] : m_poses)
		{
			f << "VERTEX_SE3:QUAT " << id << ' ';
			writePose(f, T);
			f << '\n';
		}
		for (KeyFrameId id : m_fixed) f << "FIX " << id << '\n';
		for (const auto& e : m_edges)
		{
			if (e.kind == EdgeKind::Loop) f << "# loop\n";
			else if (e.kind == EdgeKind::Covisibility) f << "# covisibility\n";
			f << "EDGE_SE3:QUAT " << e.a << ' ' << e.b << ' ';
			writePose(f, e.T_a_b);
			for (int r = 0; r < 6; ++r)
				for (int c = r; c < 6; ++c) f << ' ' << e.information(r, c);
			f << '\n';
		}
	});
}

PoseGraph PoseGraph::readG2o(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw std::runtime_error("cannot open " + path);
	PoseGraph g;
	std::string line;
	int lineNo = 0;
	EdgeKind nextKind = EdgeKind::Odometry;
	std::vector<KeyFrameId> fixed;
	while (std::getline(f, line))
	{
		++lineNo;
		try
		{
			std::istringstream is(line);
			std::string tag;
			if (!(is >> tag)) continue;
			if (tag[0] == '#')
			{
				std::string what;
				is >> what;
				if (tag == "#" && what == "loop") nextKind = EdgeKind::Loop;
				else if (tag == "#" && what == "covisibility") nextKind = EdgeKind::Covisibility;
				continue;
			}
			if (tag == "VERTEX_SE3:QUAT")
			{
				KeyFrameId id;
				if (!(is >> id)) throw std::runtime_error("expected a vertex id");
				g.addVertex(id, readPose(is));
			}
			else if (tag == "EDGE_SE3:QUAT")
			{
				PoseGraphEdge e;
				if (!(is >> e.a >> e.b)) throw std::runtime_error("expected two vertex ids");
				e.T_a_b = readPose(is);
				for (int r = 0; r < 6; ++r)
					for (int c = r; c < 6; ++c)
					{
						if (!(is >> e.information(r, c))) throw std::runtime_error("expected 21 information entries");
						e.information(c, r) = e.information(r, c);
					}
				e.kind = nextKind;
				nextKind = EdgeKind::Odometry;
				g.addEdge(e);
			}
			else if (tag == "FIX")
			{
				KeyFrameId id;
				while (is >> id) fixed.push_back(id);
			}
			else
				throw std::runtime_error("unsupported element " + tag);
		}
		catch (const std::exception& e)
		{
			throw std::runtime_error(path + ":" + std::to_string(lineNo) + ": " + e.what());
		}
	}
	for (KeyFrameId id : fixed) g.setFixed(id);
	return g;
}

}  // namespace keygrid::loop

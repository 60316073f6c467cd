#include "Parallel.h"

#include <keygrid/sim/Renderer.h>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace keygrid::sim
{
namespace
{
/** Pixel rectangle covering the projection of the part of the object's bounding box in front
 * of the near plane: projected corners plus the points where box edges cross the near plane.
 * Returns false when nothing is in front of the camera or the rectangle misses the image. */
bool screenRect(
	const Shape& shape, const Eigen::Isometry3d& T_cam_obj, const core::RgbdCamera& cam,
	double nearZ, Renderer::PreparedObject& p)
{
	const auto corners = shape.boundingCorners();
	std::array<Eigen::Vector3d, 8> c;
	for (int i = 0; i < 8; i++) c[i] = T_cam_obj * corners[i];
	double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
	bool any = false;
	auto add = [&](const Eigen::Vector3d& q) {
		const double u = cam.fx * q.x() / q.z() + cam.cx, v = cam.fy * q.y() / q.z() + cam.cy;
		umin = std::min(umin, u);
		umax = std::max(umax, u);
		vmin = std::min(vmin, v);
		vmax = std::max(vmax, v);
		any = true;
	};
	for (const auto& q : c)
		if (q.z() >= nearZ) add(q);
	// Box edges join corners whose indices differ in one bit.
	for (int i = 0; i < 8; i++)
		for (int bit = 1; bit < 8; bit <<= 1)
		{
			const int j = i | bit;
			if (j == i) continue;
			const double zi = c[i].z() - nearZ, zj = c[j].z() - nearZ;
			if ((zi < 0) == (zj < 0)) continue;
			const double s = zi / (zi - zj);
			add(c[i] + s * (c[j] - c[i]));
		}
	if (!any) return false;
	// fy may be negative (ICL): swap so that vmin <= vmax still holds.
	if (vmin > vmax) std::swap(vmin, vmax);
	if (umin > umax) std::swap(umin, umax);
	const double W = cam.width, H = cam.height;
	if (umax < -1 || vmax < -1 || umin > W || vmin > H) return false;
	p.x0 = static_cast<int>(std::max(0.0, std::floor(umin)));
	p.x1 = static_cast<int>(std::min(W - 1, std::ceil(umax)));
	p.y0 = static_cast<int>(std::max(0.0, std::floor(vmin)));
	p.y1 = static_cast<int>(std::min(H - 1, std::ceil(vmax)));
	return p.x0 <= p.x1 && p.y0 <= p.y1;
}
}  // namespace

Renderer::Renderer(const Scene& scene, const RenderOptions& opts) : m_scene(scene), m_opts(opts)
{
	if (!(opts.nearClip > 0)) throw std::invalid_argument("nearClip must be > 0");
	const core::RgbdCamera& cam = scene.camera;
	if (cam.hasDistortion())
	{
		// Undistort every pixel centre once: the ray of pixel (u, v) is (x_n, y_n, 1).
		std::vector<cv::Point2d> px, norm;
		px.reserve(std::size_t(cam.width) * cam.height);
		for (unsigned v = 0; v < cam.height; v++)
			for (unsigned u = 0; u < cam.width; u++) px.emplace_back(u, v);
		const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
		cv::undistortPoints(px, norm, K, std::vector<double>(cam.dist.begin(), cam.dist.end()));
		m_rays.resize(2 * norm.size());
		for (std::size_t i = 0; i < norm.size(); i++)
		{
			m_rays[2 * i] = norm[i].x;
			m_rays[2 * i + 1] = norm[i].y;
		}
	}
}

Eigen::Isometry3d Renderer::toIsometry(const mrpt::poses::CPose3D& p)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	const auto& R = p.getRotationMatrix();
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) T.linear()(r, c) = R(r, c);
	T.translation() = Eigen::Vector3d(p.x(), p.y(), p.z());
	return T;
}

void Renderer::render(const mrpt::poses::CPose3D& T_world_cam, double t, RenderOutput& out) const
{
	render(toIsometry(T_world_cam), t, out);
}

std::vector<Renderer::PreparedObject> Renderer::prepare(const Eigen::Isometry3d& T_world_cam, double t) const
{
	const core::RgbdCamera& cam = m_scene.camera;
	const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
	const Eigen::Vector3d light_world = m_scene.options.lightDirection.normalized();
	std::vector<PreparedObject> objs;
	objs.reserve(m_scene.objects.size());
	for (std::size_t i = 0; i < m_scene.objects.size(); i++)
	{
		const SceneObject& o = m_scene.objects[i];
		if (!o.visibleAt(t)) continue;
		const Eigen::Isometry3d T_world_obj = o.poseAt(t);
		const Eigen::Isometry3d T_cam_obj = T_cam_world * T_world_obj;
		PreparedObject p;
		if (m_rays.empty())
		{
			if (!screenRect(o.shape, T_cam_obj, cam, m_opts.nearClip, p)) continue;
		}
		else
		{
			p.x0 = p.y0 = 0;  // distorted camera: no culling
			p.x1 = static_cast<int>(cam.width) - 1;
			p.y1 = static_cast<int>(cam.height) - 1;
		}
		p.object = static_cast<int>(i);
		p.shape = &o.shape;
		p.R_obj_cam = T_cam_obj.linear().transpose();
		p.o_obj = -(p.R_obj_cam * T_cam_obj.translation());
		p.n_light_obj = T_world_obj.linear().transpose() * light_world;
		objs.push_back(p);
	}
	return objs;
}

void Renderer::allocate(RenderOutput& out) const
{
	const int W = static_cast<int>(m_scene.camera.width), H = static_cast<int>(m_scene.camera.height);
	out.colour.create(H, W, CV_8UC3);
	out.depth.create(H, W, CV_32FC1);
	out.cosIncidence.create(H, W, CV_32FC1);
	out.objectIndex.create(H, W, CV_32SC1);
}

void Renderer::render(const Eigen::Isometry3d& T_world_cam, double t, RenderOutput& out) const
{
	allocate(out);
	const auto objs = prepare(T_world_cam, t);
	parallelRows(static_cast<int>(m_scene.camera.height), m_opts.threads, [&](int r0, int r1) { renderRows(objs, r0, r1, out); });
}

void Renderer::renderRollingShutter(
	const std::function<Eigen::Isometry3d(double)>& poseAt, double t, double readout, RenderOutput& out) const
{
	if (!(readout >= 0)) throw std::invalid_argument("renderRollingShutter: readout = " + std::to_string(readout) + " s (must be >= 0)");
	allocate(out);
	const int H = static_cast<int>(m_scene.camera.height);
	parallelRows(H, m_opts.threads, [&](int r0, int r1) {
		for (int y = r0; y < r1; y++)
		{
			// Row y is exposed at t + (y / H - 1/2) readout (RollingShutter.h in libs/sfm).
			const double ty = t + (static_cast<double>(y) / H - 0.5) * readout;
			renderRows(prepare(poseAt(ty), ty), y, y + 1, out);
		}
	});
}

void Renderer::renderRows(const std::vector<PreparedObject>& objs, int r0, int r1, RenderOutput& out) const
{
	const core::RgbdCamera& cam = m_scene.camera;
	const int W = static_cast<int>(cam.width);
	const core::PinholeIntrinsics K = cam.pinhole();
	std::vector<double> rayX(W);
	for (int x = 0; x < W; x++) rayX[x] = K.rayX(x);
	const bool distorted = !m_rays.empty();
	// Ray of pixel (x, y) in the optical frame, z = 1.
	auto ray = [&](int x, int y, double ry) {
		if (!distorted) return Eigen::Vector3d(rayX[x], ry, 1.0);
		const double* r = &m_rays[2 * (static_cast<std::size_t>(y) * W + x)];
		return Eigen::Vector3d(r[0], r[1], 1.0);
	};
	const double ambient = m_scene.options.ambient;
	const double nearZ = m_opts.nearClip;

	std::vector<double> zbuf(W);
	std::vector<int> hitObj(W), hitFace(W);
	for (int y = r0; y < r1; y++)
	{
		std::fill(zbuf.begin(), zbuf.end(), std::numeric_limits<double>::infinity());
		std::fill(hitObj.begin(), hitObj.end(), -1);
		const double ry = K.rayY(y);
		for (std::size_t k = 0; k < objs.size(); k++)
		{
			const PreparedObject& p = objs[k];
			if (y < p.y0 || y > p.y1) continue;
			const Eigen::Vector3d base = p.R_obj_cam.col(1) * ry + p.R_obj_cam.col(2);
			for (int x = p.x0; x <= p.x1; x++)
			{
				const Eigen::Vector3d d =
					distorted ? Eigen::Vector3d(p.R_obj_cam * ray(x, y, ry))
							  : Eigen::Vector3d(p.R_obj_cam.col(0) * rayX[x] + base);
				LocalHit h;
				if (p.shape->intersect(p.o_obj, d, nearZ, zbuf[x], h))
				{
					zbuf[x] = h.t;
					hitObj[x] = static_cast<int>(k);
					hitFace[x] = h.face;
				}
			}
		}
		// Shade the winners.
		auto* colour = out.colour.ptr<cv::Vec3b>(y);
		auto* depth = out.depth.ptr<float>(y);
		auto* cosI = out.cosIncidence.ptr<float>(y);
		auto* index = out.objectIndex.ptr<int>(y);
		for (int x = 0; x < W; x++)
		{
			if (hitObj[x] < 0)
			{
				colour[x] = cv::Vec3b(0, 0, 0);
				depth[x] = 0;
				cosI[x] = 0;
				index[x] = -1;
				continue;
			}
			const PreparedObject& p = objs[hitObj[x]];
			const double z = zbuf[x];
			const Eigen::Vector3d d = p.R_obj_cam * ray(x, y, ry);
			const Eigen::Vector3d q = p.o_obj + z * d;
			Eigen::Vector3d n = p.shape->normal(q, hitFace[x]);
			if (n.dot(d) > 0) n = -n;  // two-sided quads: the face towards the camera
			const double c = std::abs(n.dot(d)) / d.norm();
			const Eigen::Vector2d uv = p.shape->surfaceUV(q, hitFace[x]);
			// Surface metres under one pixel: z / f, stretched by the slant.
			const double footprint = z * d.norm() / (std::abs(cam.fx) * std::max(c, 0.2));
			float bgr[3];
			m_scene.textures[m_scene.objects[p.object].texture]->sample(
				uv.x(), uv.y(), footprint, bgr);
			const double shade =
				ambient + (1.0 - ambient) * std::max(0.0, n.dot(p.n_light_obj));
			for (int ch = 0; ch < 3; ch++)
				colour[x][ch] = static_cast<unsigned char>(
					std::clamp(std::lround(bgr[ch] * shade), 0L, 255L));
			depth[x] = static_cast<float>(z);
			cosI[x] = static_cast<float>(c);
			index[x] = p.object;
		}
	}
}

}  // namespace keygrid::sim

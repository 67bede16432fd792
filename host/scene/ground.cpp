#include "scene/ground.h"

#include <algorithm>
#include <cmath>

namespace raysort {

GroundGrid::GroundGrid(const Mesh& mesh, const std::vector<Affine>& transforms) {
  for (const auto& xf : transforms)
    for (const auto& t : mesh.triangles) {
      a_.push_back(xf.apply(mesh.positions[t[0]]));
      b_.push_back(xf.apply(mesh.positions[t[1]]));
      c_.push_back(xf.apply(mesh.positions[t[2]]));
    }
  if (a_.empty()) return;
  double max_x = -1e300, max_z = -1e300;
  min_x_ = min_z_ = 1e300;
  for (std::size_t i = 0; i < a_.size(); ++i)
    for (const Vec3* p : {&a_[i], &b_[i], &c_[i]}) {
      min_x_ = std::min(min_x_, double((*p)[0]));
      max_x = std::max(max_x, double((*p)[0]));
      min_z_ = std::min(min_z_, double((*p)[2]));
      max_z = std::max(max_z, double((*p)[2]));
    }
  // About two triangles per cell, cells as square as the footprint allows.
  double w = std::max(max_x - min_x_, 1e-9), d = std::max(max_z - min_z_, 1e-9);
  double cells = std::max(1.0, a_.size() / 2.0);
  double side = std::sqrt(w * d / cells);
  nx_ = static_cast<std::uint32_t>(std::clamp(std::ceil(w / side), 1.0, 4096.0));
  nz_ = static_cast<std::uint32_t>(std::clamp(std::ceil(d / side), 1.0, 4096.0));
  cell_x_ = w / nx_;
  cell_z_ = d / nz_;
  auto cell_range = [&](std::size_t i, std::uint32_t& x0, std::uint32_t& x1, std::uint32_t& z0, std::uint32_t& z1) {
    double lx = std::min({a_[i][0], b_[i][0], c_[i][0]}), hx = std::max({a_[i][0], b_[i][0], c_[i][0]});
    double lz = std::min({a_[i][2], b_[i][2], c_[i][2]}), hz = std::max({a_[i][2], b_[i][2], c_[i][2]});
    auto cx = [&](double x) { return static_cast<std::uint32_t>(std::clamp((x - min_x_) / cell_x_, 0.0, nx_ - 1.0)); };
    auto cz = [&](double z) { return static_cast<std::uint32_t>(std::clamp((z - min_z_) / cell_z_, 0.0, nz_ - 1.0)); };
    x0 = cx(lx), x1 = cx(hx), z0 = cz(lz), z1 = cz(hz);
  };
  cell_start_.assign(std::size_t(nx_) * nz_ + 1, 0);
  std::uint32_t x0, x1, z0, z1;
  for (std::size_t i = 0; i < a_.size(); ++i) {
    cell_range(i, x0, x1, z0, z1);
    for (std::uint32_t z = z0; z <= z1; ++z)
      for (std::uint32_t x = x0; x <= x1; ++x) ++cell_start_[std::size_t(z) * nx_ + x + 1];
  }
  for (std::size_t i = 1; i < cell_start_.size(); ++i) cell_start_[i] += cell_start_[i - 1];
  cell_tris_.resize(cell_start_.back());
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < a_.size(); ++i) {
    cell_range(i, x0, x1, z0, z1);
    for (std::uint32_t z = z0; z <= z1; ++z)
      for (std::uint32_t x = x0; x <= x1; ++x) cell_tris_[fill[std::size_t(z) * nx_ + x]++] = static_cast<std::uint32_t>(i);
  }
}

std::optional<float> GroundGrid::height(double x, double z, double y_lo, double y_hi) const {
  if (a_.empty()) return std::nullopt;
  double fx = (x - min_x_) / cell_x_, fz = (z - min_z_) / cell_z_;
  if (fx < 0 || fz < 0 || fx > nx_ || fz > nz_) return std::nullopt;
  auto cx = std::min(static_cast<std::uint32_t>(fx), nx_ - 1), cz = std::min(static_cast<std::uint32_t>(fz), nz_ - 1);
  std::size_t cell = std::size_t(cz) * nx_ + cx;
  std::optional<float> best;
  for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
    std::uint32_t i = cell_tris_[k];
    // Barycentric coordinates of (x, z) in the triangle's x/z projection.
    double ax = a_[i][0], az = a_[i][2], bx = b_[i][0], bz = b_[i][2], qx = c_[i][0], qz = c_[i][2];
    double det = (bx - ax) * (qz - az) - (qx - ax) * (bz - az);
    if (std::fabs(det) < 1e-30) continue;  // vertical or degenerate: no single height
    double u = ((x - ax) * (qz - az) - (qx - ax) * (z - az)) / det;
    double v = ((bx - ax) * (z - az) - (x - ax) * (bz - az)) / det;
    const double eps = -1e-9;
    if (u < eps || v < eps || u + v > 1.0 - eps) continue;
    double y = a_[i][1] + u * (double(b_[i][1]) - a_[i][1]) + v * (double(c_[i][1]) - a_[i][1]);
    if (y < y_lo || y > y_hi) continue;
    if (!best || y > *best) best = static_cast<float>(y);
  }
  return best;
}

}  // namespace raysort

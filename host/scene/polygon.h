#pragma once
// Polygons to triangles, the one rule for every format with n-gon faces (OBJ, PLY): a quad along
// its shorter diagonal (as tinyobjloader does), a larger polygon as a fan from its first vertex,
// so an n-gon always gives n − 2 triangles and the same face gives the same triangles in any format.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace raysort {

// Calls emit(a, b, c) for each triangle of the polygon with vertex indices corner[0..n) (n ≥ 3).
template <class Corner, class Emit>
void triangulate_polygon(const std::vector<Vec3>& positions, std::size_t n, Corner corner, Emit emit) {
  if (n == 4) {
    const std::uint32_t q[4] = {corner(0), corner(1), corner(2), corner(3)};
    auto dist2 = [&](std::uint32_t a, std::uint32_t b) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k) {
        double d = double(positions[a][k]) - positions[b][k];
        s += d * d;
      }
      return s;
    };
    if (dist2(q[0], q[2]) < dist2(q[1], q[3])) {
      emit(q[0], q[1], q[2]);
      emit(q[0], q[2], q[3]);
    } else {
      emit(q[0], q[1], q[3]);
      emit(q[1], q[2], q[3]);
    }
    return;
  }
  const std::uint32_t first = corner(0);
  for (std::size_t k = 2; k < n; ++k) emit(first, corner(k - 1), corner(k));
}

}  // namespace raysort

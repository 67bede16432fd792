#include "trace/exact_oracle.h"

#include <fmt/format.h>
#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace raysort {

namespace {

using D3 = std::array<double, 3>;
using Q3 = std::array<mpq_class, 3>;

constexpr double kFloatUlp = 1.0 / 16777216.0;  // 2^-24: half an ulp of 1 in float, relative

template <class T>
std::array<T, 3> sub(const std::array<T, 3>& a, const std::array<T, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
template <class T>
std::array<T, 3> cross(const std::array<T, 3>& a, const std::array<T, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
template <class T>
T dot(const std::array<T, 3>& a, const std::array<T, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const D3& a) { return std::sqrt(dot(a, a)); }
double max_abs(const D3& a) { return std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(a[2])}); }

D3 to_d3(const Vec3& v) { return {v[0], v[1], v[2]}; }
Q3 to_q3(const D3& v) { return {mpq_class(v[0]), mpq_class(v[1]), mpq_class(v[2])}; }

// The ray's segment [t0, t1] against a box widened by pad: whether they meet.
bool segment_meets_box(const D3& o, const D3& d, double t0, double t1, const RsBvhNode& n) {
  const double pad = 1e-4 * (std::max({std::fabs(n.bmin[0]), std::fabs(n.bmin[1]), std::fabs(n.bmin[2]),
                                       std::fabs(n.bmax[0]), std::fabs(n.bmax[1]), std::fabs(n.bmax[2])}) +
                             1e-30);
  for (int i = 0; i < 3; ++i) {
    const double lo = n.bmin[i] - pad, hi = n.bmax[i] + pad;
    if (d[i] == 0.0) {
      if (o[i] < lo || o[i] > hi) return false;
      continue;
    }
    double a = (lo - o[i]) / d[i], b = (hi - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a), t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

// One candidate triangle against the ray: the Möller–Trumbore quantities in double to find what
// is far from the triangle, then exactly.
struct Candidate {
  ExactTruth::Surface surface;
  mpq_class t_exact;    // valid when surface.hit
  double inside = 0.0;  // distance inside the triangle and [tmin, tmax] (negative: outside)
};

// How far (as a distance) the plane point with barycentrics (1-u-v, u, v) lies outside the
// triangle; negative: inside, by that much from the nearest edge.
double barycentric_gap(double u, double v, const D3& e1, const D3& e2) {
  const double area2 = norm(cross(e1, e2));  // twice the area
  const D3 e12 = sub(e2, e1);
  // Height of each vertex over its opposite edge: λ · height is the distance to that edge.
  const double h0 = area2 / std::max(norm(e12), 1e-300), h1 = area2 / std::max(norm(e2), 1e-300),
               h2 = area2 / std::max(norm(e1), 1e-300);
  return std::max({-(1.0 - u - v) * h0, -u * h1, -v * h2});
}

}  // namespace

const char* verdict_name(Verdict v) { return v == Verdict::Right ? "right" : v == Verdict::Tie ? "tie" : "wrong"; }

std::size_t ExactTruth::nearest_count() const {
  return static_cast<std::size_t>(std::count_if(surfaces.begin(), surfaces.end(), [](const Surface& s) { return s.nearest; }));
}
bool ExactTruth::hit() const {
  return std::any_of(surfaces.begin(), surfaces.end(), [](const Surface& s) { return s.hit; });
}
double ExactTruth::nearest_t() const {
  for (const auto& s : surfaces)
    if (s.nearest) return s.t;
  return RS_T_FAR;
}
std::string ExactTruth::describe() const {
  std::string out;
  for (const auto& s : surfaces)
    out += fmt::format("tri {} at t {:.9g}: {}{}{} (gap {:.3g}, tolerance {:.3g})\n", s.tri, s.t,
                       s.hit ? "hit" : "near miss", s.firm ? ", firm" : "", s.nearest ? ", nearest" : "", s.gap,
                       tolerance);
  return out.empty() ? "nothing within the tolerance\n" : out;
}

ExactOracle::ExactOracle(const Scene::Flat& tris, const Bvh& bvh) : tris_(tris), bvh_(bvh) {}

ExactTruth ExactOracle::truth(const RsRay& ray, bool any_hit) const {
  ExactTruth truth;
  truth.any_hit = any_hit;
  const D3 o{ray.o[0], ray.o[1], ray.o[2]}, d{ray.d[0], ray.d[1], ray.d[2]};
  const double dlen = norm(d);
  const double tmin = ray.tmin, tmax = ray.tmax;
  // The tolerance: kUlps float ulps of the coordinates' magnitude where the ray meets things. The
  // origin's magnitude, raised below by each surface's.
  double scale = std::max(max_abs(o), 1e-30);
  const double slack = 1e-4 * (scale + 1.0) / std::max(dlen, 1e-300);

  const Q3 qo = to_q3(o), qd = to_q3(d);  // the ray as rationals, once
  std::vector<Candidate> found;
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty() && !bvh_.nodes.empty()) {
    const RsBvhNode& n = bvh_.nodes[stack.back()];
    stack.pop_back();
    if (!segment_meets_box(o, d, tmin - slack, tmax + slack, n)) continue;
    if (n.count == 0) {
      stack.push_back(n.first);
      stack.push_back(n.first + 1);
      continue;
    }
    for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
      const std::uint32_t id = bvh_.triangles[k].id;
      const D3 v0 = to_d3(tris_.v0[id]), v1 = to_d3(tris_.v1[id]), v2 = to_d3(tris_.v2[id]);
      const D3 e1 = sub(v1, v0), e2 = sub(v2, v0), s = sub(o, v0);
      const D3 p = cross(d, e2), q = cross(s, e1);
      const double det = dot(e1, p);
      Candidate c;
      c.surface.tri = id;
      if (det != 0.0) {  // a rough look in double: keep only what may be within the tolerance
        const double u = dot(s, p) / det, v = dot(d, q) / det, t = dot(e2, q) / det;
        const D3 at{o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        const double tol = ExactOracle::kUlps * kFloatUlp * std::max(scale, max_abs(at));
        const double gap_t = std::max({(tmin - t) * dlen, (t - tmax) * dlen, 0.0});
        if (!std::isfinite(t) || std::max(barycentric_gap(u, v, e1, e2), gap_t) > 4 * tol) continue;
      }
      // Exactly: det, u·det, v·det, t·det as rationals of the float inputs.
      ++exact_tests_;
      const Q3 qv0 = to_q3(v0), qe1 = sub(to_q3(v1), qv0), qe2 = sub(to_q3(v2), qv0);
      const Q3 qs = sub(qo, qv0), qp = cross(qd, qe2), qq = cross(qs, qe1);
      const mpq_class D = dot(qe1, qp);
      if (sgn(D) == 0) continue;  // in the plane, or a zero-area triangle: no area to hit
      const mpq_class u = dot(qs, qp) / D, v = dot(qd, qq) / D, t = dot(qe2, qq) / D;
      const mpq_class w = 1 - u - v;
      c.surface.hit = sgn(u) >= 0 && sgn(v) >= 0 && sgn(w) >= 0 && t > mpq_class(tmin) && t < mpq_class(tmax);
      c.t_exact = t;
      c.surface.t = t.get_d();
      const D3 at{o[0] + c.surface.t * d[0], o[1] + c.surface.t * d[1], o[2] + c.surface.t * d[2]};
      scale = std::max(scale, max_abs(at));
      // How far inside the triangle and [tmin, tmax] the point lies, as a distance (negative:
      // outside by that much).
      c.inside = std::min({-barycentric_gap(u.get_d(), v.get_d(), e1, e2), (c.surface.t - tmin) * dlen,
                           (tmax - c.surface.t) * dlen});
      c.surface.gap = c.surface.hit ? 0.0 : std::max(0.0, -c.inside);
      found.push_back(std::move(c));
    }
  }
  truth.tolerance = ExactOracle::kUlps * kFloatUlp * scale;
  truth.dir_length = dlen;
  // Firm hits are inside by more than the tolerance.
  const mpq_class* nearest = nullptr;
  for (auto& c : found) {
    if (!c.surface.hit) continue;
    c.surface.firm = c.inside >= truth.tolerance;
    if (!nearest || c.t_exact < *nearest) nearest = &c.t_exact;
  }
  for (auto& c : found) {
    c.surface.nearest = c.surface.hit && nearest && c.t_exact == *nearest;
    if (c.surface.hit || c.surface.gap <= truth.tolerance * 4) truth.surfaces.push_back(c.surface);
  }
  std::stable_sort(truth.surfaces.begin(), truth.surfaces.end(), [](const auto& a, const auto& b) {
    return a.nearest != b.nearest ? a.nearest : a.t < b.t;
  });
  return truth;
}

Verdict ExactOracle::judge(const ExactTruth& truth, const RsHit& answer) {
  const double tol = truth.tolerance;
  // A point where two or more triangles meet at exactly the nearest t (a shared edge or vertex of
  // the surface) blocks the ray as firmly as a triangle's inside: skipping it is a leak.
  const bool shared_nearest = truth.nearest_count() >= 2;
  auto blocks = [&](const ExactTruth::Surface& s) { return s.firm || (s.nearest && shared_nearest); };
  const bool blocked = std::any_of(truth.surfaces.begin(), truth.surfaces.end(), blocks);
  if (answer.tri == RS_NO_HIT) {  // free, or a closest-hit miss
    if (!truth.hit()) return Verdict::Right;
    return blocked ? Verdict::Wrong : Verdict::Tie;
  }
  if (truth.any_hit) {  // occluded
    if (truth.hit()) return Verdict::Right;
    const bool near = std::any_of(truth.surfaces.begin(), truth.surfaces.end(), [&](const auto& s) { return s.gap <= tol; });
    return near ? Verdict::Tie : Verdict::Wrong;
  }
  const auto it = std::find_if(truth.surfaces.begin(), truth.surfaces.end(),
                               [&](const auto& s) { return s.tri == answer.tri; });
  if (it == truth.surfaces.end() || it->gap > tol) return Verdict::Wrong;  // not met, even within precision
  if (it->nearest) return shared_nearest ? Verdict::Tie : Verdict::Right;
  // Within precision of a surface: wrong only if something that blocks lies clearly in front of it.
  for (const auto& s : truth.surfaces)
    if (blocks(s) && (it->t - s.t) * truth.dir_length > tol) return Verdict::Wrong;
  return Verdict::Tie;
}

}  // namespace raysort

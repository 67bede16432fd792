#include "trace/order_agreement.h"

#include <cstring>

#include "intersect.h"

namespace raysort {

bool fast_test_gives(const Scene::Flat& tris, const RsRay& ray, const RsHit& h) {
  if (h.tri == RS_NO_HIT || h.tri >= tris.size()) return false;
  RsTriangle t{};
  for (int k = 0; k < 3; ++k) t.v0[k] = tris.v0[h.tri][k], t.v1[k] = tris.v1[h.tri][k], t.v2[k] = tris.v2[h.tri][k];
  float tt = 0.0f, u = 0.0f, v = 0.0f;
  return rs_intersect_triangle(rs_prepare_ray(ray), &t, ray.tmax, &tt, &u, &v) && tt == h.t && u == h.u && v == h.v;
}

bool answers_agree(const RsHit& other, const RsHit& nosort, const RsRay& ray, bool any_hit, TraceVariant variant,
                   const ExactOracle& oracle, const Scene::Flat& tris) {
  if (std::memcmp(&other, &nosort, sizeof(RsHit)) == 0) return true;
  if (ExactOracle::judge(oracle.truth(ray, any_hit), other) != Verdict::Wrong) return true;
  return variant == TraceVariant::Fast && !any_hit && other.t <= nosort.t && fast_test_gives(tris, ray, other);
}

}  // namespace raysort

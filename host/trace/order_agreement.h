#pragma once
// Whether two answers a traversal gave one ray in two orders agree (run's check that a sorted trace
// reproduces NoSort's hits; docs/trace.md, "Trace classes"). A single ray meets its nodes in the same
// order whatever the batch's order, so its answer is the same bit for bit. A ray in a packet or a
// stream meets them in an order its companions decide, so where two surfaces lie within float
// precision of each other it may keep the other one, and in the fast variant it may meet a
// triangle that Möller–Trumbore hits near an edge and exact arithmetic misses (breakfast_room's
// slivers: 1 of 2,073,600 primary rays in HCC order, packet16).
#include "scene/scene.h"
#include "shared.h"
#include "trace/exact_oracle.h"
#include "trace/tracer.h"

namespace raysort {

// Whether the fast variant's own triangle test (rs_intersect_triangle, what each lane of a packet and
// each ray of a stream runs) gives `ray` the answer h: a hit on h.tri at exactly h.t, h.u, h.v.
bool fast_test_gives(const Scene::Flat& tris, const RsRay& ray, const RsHit& h);

// Whether `other`, a ray's answer in another order, agrees with `nosort`: equal bit for bit; or
// judged right or a tie by the exact oracle; or, fast variant and closest hit only, nearer than
// NoSort's and what the fast triangle test itself gives (a near-edge hit met in this order only).
bool answers_agree(const RsHit& other, const RsHit& nosort, const RsRay& ray, bool any_hit, TraceVariant variant,
                   const ExactOracle& oracle, const Scene::Flat& tris);

}  // namespace raysort

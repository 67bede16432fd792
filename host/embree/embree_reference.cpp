// The Embree anchor: Embree 3 traces the same triangles and rays as the OpenCL kernel (issue 9).
#include "embree/embree_reference.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <thread>

#include "util/error.h"

namespace raysort {

namespace {

// Errors Embree reports through its callback, collected until checked.
struct ErrorSink {
  std::mutex mutex;
  std::string first;
};

void on_embree_error(void* user, RTCError code, const char* str) {
  auto* sink = static_cast<ErrorSink*>(user);
  std::lock_guard<std::mutex> lock(sink->mutex);
  if (sink->first.empty()) sink->first = fmt::format("Embree error {}: {}", static_cast<int>(code), str ? str : "");
}

ErrorSink& error_sink() {
  static ErrorSink sink;
  return sink;
}

void check(RTCDevice device, const char* doing) {
  RTCError code = rtcGetDeviceError(device);
  std::string msg;
  {
    std::lock_guard<std::mutex> lock(error_sink().mutex);
    msg.swap(error_sink().first);
  }
  if (code != RTC_ERROR_NONE || !msg.empty())
    throw Error(fmt::format("{} failed: {}", doing, msg.empty() ? fmt::format("Embree error {}", static_cast<int>(code)) : msg));
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Runs body(begin, end) over [0, n) on `threads` threads (the caller is one of them), each taking
// contiguous chunks from a shared counter so that cheap rays (sky) do not leave a thread idle.
template <class Body>
void parallel_chunks(std::size_t n, unsigned threads, const Body& body) {
  constexpr std::size_t kChunk = 4096;
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (;;) {
      std::size_t begin = next.fetch_add(kChunk, std::memory_order_relaxed);
      if (begin >= n) return;
      body(begin, std::min(n, begin + kChunk));
    }
  };
  const unsigned extra = n > kChunk ? std::min<std::size_t>(threads, (n + kChunk - 1) / kChunk) - 1 : 0;
  std::vector<std::thread> pool;
  pool.reserve(extra);
  for (unsigned i = 0; i < extra; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace

std::string EmbreeScene::version() { return RTC_VERSION_STRING; }

EmbreeScene::EmbreeScene(const Scene::Flat& tris, unsigned threads) {
  threads_ = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  const std::string config = fmt::format("threads={}", threads_);
  device_ = rtcNewDevice(config.c_str());
  if (!device_) throw Error(fmt::format("rtcNewDevice(\"{}\") failed: {}", config, static_cast<int>(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(device_, on_embree_error, &error_sink());

  scene_ = rtcNewScene(device_);
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  const std::size_t n = tris.size();
  if (n > 0) {
    // Unshared vertices (3 per triangle): the same floats as our RsTriangle, and primID = index.
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    check(device_, "Embree geometry buffers");
    for (std::size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        v[9 * i + k] = tris.v0[i][k];
        v[9 * i + 3 + k] = tris.v1[i][k];
        v[9 * i + 6 + k] = tris.v2[i][k];
      }
      for (unsigned k = 0; k < 3; ++k) idx[3 * i + k] = static_cast<unsigned>(3 * i + k);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene_, geom, 0);
    rtcReleaseGeometry(geom);
    check(device_, "Embree geometry");
  }
  auto t0 = std::chrono::steady_clock::now();
  rtcCommitScene(scene_);
  build_ms_ = ms_since(t0);
  check(device_, "Embree BVH build (rtcCommitScene)");
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

std::vector<RsHit> EmbreeScene::trace(const std::vector<RsRay>& rays, bool any_hit) const {
  std::vector<RsHit> hits(rays.size());
  RTCScene scene = scene_;
  if (any_hit) {
    parallel_chunks(rays.size(), threads_, [&](std::size_t begin, std::size_t end) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      for (std::size_t i = begin; i < end; ++i) {
        const RsRay& r = rays[i];
        alignas(16) RTCRay ray;
        ray.org_x = r.o[0], ray.org_y = r.o[1], ray.org_z = r.o[2], ray.tnear = r.tmin;
        ray.dir_x = r.d[0], ray.dir_y = r.d[1], ray.dir_z = r.d[2], ray.time = 0.0f;
        ray.tfar = r.tmax, ray.mask = 0xFFFFFFFFu, ray.id = 0, ray.flags = 0;
        rtcOccluded1(scene, &ctx, &ray);
        // rtcOccluded1 sets tfar to -inf on any hit and leaves it otherwise.
        const bool occluded = !(ray.tfar >= 0.0f);
        hits[i] = RsHit{occluded ? 0.0f : r.tmax, occluded ? kEmbreeOccluded : RS_NO_HIT, 0.0f, 0.0f};
      }
    });
  } else {
    parallel_chunks(rays.size(), threads_, [&](std::size_t begin, std::size_t end) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      for (std::size_t i = begin; i < end; ++i) {
        const RsRay& r = rays[i];
        alignas(16) RTCRayHit rh;
        rh.ray.org_x = r.o[0], rh.ray.org_y = r.o[1], rh.ray.org_z = r.o[2], rh.ray.tnear = r.tmin;
        rh.ray.dir_x = r.d[0], rh.ray.dir_y = r.d[1], rh.ray.dir_z = r.d[2], rh.ray.time = 0.0f;
        rh.ray.tfar = r.tmax, rh.ray.mask = 0xFFFFFFFFu, rh.ray.id = 0, rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
          hits[i] = RsHit{r.tmax, RS_NO_HIT, 0.0f, 0.0f};
        else
          hits[i] = RsHit{rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v};
      }
    });
  }
  return hits;
}

HitAgreement compare_with_embree(const std::vector<RsHit>& ours, const std::vector<RsHit>& embree, bool any_hit) {
  if (ours.size() != embree.size())
    throw Error(fmt::format("compare_with_embree: {} hits against {}", ours.size(), embree.size()));
  HitAgreement a;
  a.any_hit = any_hit;
  a.rays = ours.size();
  for (std::size_t i = 0; i < ours.size(); ++i) {
    const RsHit& o = ours[i];
    const RsHit& e = embree[i];
    const bool oh = o.tri != RS_NO_HIT, eh = e.tri != RS_NO_HIT;
    if (oh && !eh) {
      ++a.ours_only;
    } else if (!oh && eh) {
      ++a.embree_only;
    } else if (!oh || any_hit) {
      ++a.same;  // both missed, or both occluded
    } else {
      const double scale = std::max(1.0, static_cast<double>(std::fabs(o.t)));
      const double rel = std::fabs(static_cast<double>(o.t) - static_cast<double>(e.t)) / scale;
      if (o.tri == e.tri) {
        ++a.same;
        a.max_rel_dt = std::max(a.max_rel_dt, rel);
      } else if (rel <= HitAgreement::kTieRelT) {
        auto edge = [](const RsHit& h) { return std::min(std::min(h.u, h.v), 1.0f - h.u - h.v); };
        if (std::min(edge(o), edge(e)) <= HitAgreement::kEdgeBary)
          ++a.tie_edge;
        else
          ++a.tie_overlap;
      } else {
        ++a.other_tri;
      }
    }
  }
  return a;
}

std::string HitAgreement::describe() const {
  std::vector<std::string> parts;
  if (any_hit) {
    if (ours_only) parts.push_back(fmt::format("{} occluded for ours / free for Embree", ours_only));
    if (embree_only) parts.push_back(fmt::format("{} free for ours / occluded for Embree", embree_only));
  } else {
    if (tie_edge) parts.push_back(fmt::format("{} other triangle at the same t on an edge (a tie on a shared edge/vertex)", tie_edge));
    if (tie_overlap)
      parts.push_back(fmt::format("{} other triangle at the same t inside both (coplanar overlapping faces)", tie_overlap));
    if (other_tri) parts.push_back(fmt::format("{} other triangle farther apart", other_tri));
    if (ours_only) parts.push_back(fmt::format("{} ours hit / Embree missed", ours_only));
    if (embree_only) parts.push_back(fmt::format("{} Embree hit / ours missed", embree_only));
  }
  std::string s;
  for (const auto& p : parts) s += (s.empty() ? "" : ", ") + p;
  return s;
}

}  // namespace raysort

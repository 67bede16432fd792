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
#include "util/text.h"

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

// Runs body(begin, end, scratch) over [0, n) on `threads` threads (the caller is one of them), each
// taking contiguous chunks from a shared counter so that cheap rays (sky) do not leave a thread
// idle. Each thread has one Scratch (a stream's ray array) for all its chunks, so that no chunk
// allocates. Chunks are a multiple of 16 rays: only the batch's last packet can be partial.
constexpr std::size_t kChunk = 4096;
static_assert(kChunk % 16 == 0);

template <class Scratch, class Body>
void parallel_chunks(std::size_t n, unsigned threads, const Body& body) {
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    Scratch scratch{};
    for (;;) {
      std::size_t begin = next.fetch_add(kChunk, std::memory_order_relaxed);
      if (begin >= n) return;
      body(begin, std::min(n, begin + kChunk), scratch);
    }
  };
  const unsigned extra = n > kChunk ? std::min<std::size_t>(threads, (n + kChunk - 1) / kChunk) - 1 : 0;
  std::vector<std::thread> pool;
  pool.reserve(extra);
  for (unsigned i = 0; i < extra; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

struct NoScratch {};

// The i-th ray to trace: rays[order[i]], or rays[i] without an order.
struct RayAt {
  const RsRay* rays;
  const std::uint32_t* order;  // null: the rays' own order
  const RsRay& operator()(std::size_t i) const { return rays[order ? order[i] : i]; }
  // Through an order, a ray is a cache miss the traversal before it cannot hide: the loops of one
  // ray or one packet at a time fetch the rays they trace next early, as the kernels do on a CPU
  // (cl/trace.cl, "Gather on a CPU"), so that Embree's arms on a sorted order pay what ours pay.
  // Rays in their own order stream in by the hardware's prefetcher.
  void prefetch(std::size_t i, std::size_t end) const {
    if (order && i < end) __builtin_prefetch(&rays[order[i]]);
  }
};

RTCIntersectContext context_with(bool coherent) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);  // flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
  ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  return ctx;
}

// RsRay (o, tmin, d, tmax) as Embree's ray: time 0, every mask bit, no flags.
void set_ray(const RsRay& r, RTCRay& ray) {
  ray.org_x = r.o[0], ray.org_y = r.o[1], ray.org_z = r.o[2], ray.tnear = r.tmin;
  ray.dir_x = r.d[0], ray.dir_y = r.d[1], ray.dir_z = r.d[2], ray.time = 0.0f;
  ray.tfar = r.tmax, ray.mask = 0xFFFFFFFFu, ray.id = 0, ray.flags = 0;
}

// Lane k of a packet (RTCRay4/8/16: the same fields as arrays).
template <class RayK>
void set_lane(const RsRay& r, RayK& ray, unsigned k) {
  ray.org_x[k] = r.o[0], ray.org_y[k] = r.o[1], ray.org_z[k] = r.o[2], ray.tnear[k] = r.tmin;
  ray.dir_x[k] = r.d[0], ray.dir_y[k] = r.d[1], ray.dir_z[k] = r.d[2], ray.time[k] = 0.0f;
  ray.tfar[k] = r.tmax, ray.mask[k] = 0xFFFFFFFFu, ray.id[k] = 0, ray.flags[k] = 0;
}

// The hit record every path reports, from what Embree left in the ray (see trace()).
RsHit closest_hit(const RsRay& r, float tfar, unsigned geom_id, unsigned prim_id, float u, float v) {
  if (geom_id == RTC_INVALID_GEOMETRY_ID) return RsHit{r.tmax, RS_NO_HIT, 0.0f, 0.0f};
  return RsHit{tfar, prim_id, u, v};
}
RsHit occlusion_hit(const RsRay& r, float tfar) {
  // rtcOccluded* sets tfar to -inf on any hit and leaves it otherwise.
  const bool occluded = !(tfar >= 0.0f);
  return RsHit{occluded ? 0.0f : r.tmax, occluded ? kEmbreeOccluded : RS_NO_HIT, 0.0f, 0.0f};
}

void trace_single(RTCScene scene, const RayAt& at, std::size_t n, bool any_hit, bool coherent, unsigned threads,
                  RsHit* hits) {
  parallel_chunks<NoScratch>(n, threads, [&](std::size_t begin, std::size_t end, NoScratch&) {
    RTCIntersectContext ctx = context_with(coherent);
    for (std::size_t i = begin; i < end; ++i) {
      at.prefetch(i + RS_RAY_PREFETCH_DISTANCE, end);
      const RsRay& r = at(i);
      if (any_hit) {
        alignas(16) RTCRay ray;
        set_ray(r, ray);
        rtcOccluded1(scene, &ctx, &ray);
        hits[i] = occlusion_hit(r, ray.tfar);
      } else {
        alignas(16) RTCRayHit rh;
        set_ray(r, rh.ray);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &ctx, &rh);
        hits[i] = closest_hit(r, rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v);
      }
    }
  });
}

// A stream: each chunk laid out as an array of RTCRayHit (closest) or RTCRay (any hit), traced by
// one rtcIntersect1M / rtcOccluded1M call with the array's own byte stride.
void trace_stream(RTCScene scene, const RayAt& at, std::size_t n, bool any_hit, bool coherent, unsigned threads,
                  RsHit* hits) {
  if (any_hit) {
    parallel_chunks<std::vector<RTCRay>>(n, threads, [&](std::size_t begin, std::size_t end, std::vector<RTCRay>& buf) {
      RTCIntersectContext ctx = context_with(coherent);
      buf.resize(end - begin);
      for (std::size_t i = begin; i < end; ++i) set_ray(at(i), buf[i - begin]);
      rtcOccluded1M(scene, &ctx, buf.data(), static_cast<unsigned>(buf.size()), sizeof(RTCRay));
      for (std::size_t i = begin; i < end; ++i) hits[i] = occlusion_hit(at(i), buf[i - begin].tfar);
    });
  } else {
    parallel_chunks<std::vector<RTCRayHit>>(n, threads, [&](std::size_t begin, std::size_t end,
                                                              std::vector<RTCRayHit>& buf) {
      RTCIntersectContext ctx = context_with(coherent);
      buf.resize(end - begin);
      for (std::size_t i = begin; i < end; ++i) {
        RTCRayHit& rh = buf[i - begin];
        set_ray(at(i), rh.ray);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(scene, &ctx, buf.data(), static_cast<unsigned>(buf.size()), sizeof(RTCRayHit));
      for (std::size_t i = begin; i < end; ++i) {
        const RTCRayHit& rh = buf[i - begin];
        hits[i] = closest_hit(at(i), rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v);
      }
    });
  }
}

// The packet types and calls of one width.
template <unsigned K>
struct Packet;
template <>
struct Packet<4> {
  using Ray = RTCRay4;
  using RayHit = RTCRayHit4;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect4(valid, s, c, r); }
  static void occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded4(valid, s, c, r); }
};
template <>
struct Packet<8> {
  using Ray = RTCRay8;
  using RayHit = RTCRayHit8;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect8(valid, s, c, r); }
  static void occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded8(valid, s, c, r); }
};
template <>
struct Packet<16> {
  using Ray = RTCRay16;
  using RayHit = RTCRayHit16;
  static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect16(valid, s, c, r); }
  static void occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded16(valid, s, c, r); }
};

// Packets of K consecutive rays. Embree requires the valid mask and the packet aligned to the
// packet's size (16, 32, 64 bytes); lanes past the batch's end (its last packet only, chunks being
// multiples of 16) are masked off with 0 and keep the previous packet's rays, which Embree neither
// traces nor changes.
template <unsigned K>
void trace_packets(RTCScene scene, const RayAt& at, std::size_t n, bool any_hit, bool coherent, unsigned threads,
                   RsHit* hits) {
  using P = Packet<K>;
  static_assert(alignof(typename P::Ray) >= 4 * K && alignof(typename P::RayHit) >= 4 * K);
  parallel_chunks<NoScratch>(n, threads, [&](std::size_t begin, std::size_t end, NoScratch&) {
    RTCIntersectContext ctx = context_with(coherent);
    alignas(4 * K) int valid[K];
    alignas(4 * K) typename P::Ray ray{};
    alignas(4 * K) typename P::RayHit rh{};
    for (std::size_t first = begin; first < end; first += K) {
      const auto lanes = static_cast<unsigned>(std::min<std::size_t>(K, end - first));
      for (unsigned k = 0; k < K; ++k) at.prefetch(first + K + k, end);  // the next packet's rays
      for (unsigned k = 0; k < K; ++k) valid[k] = k < lanes ? -1 : 0;
      if (any_hit) {
        for (unsigned k = 0; k < lanes; ++k) set_lane(at(first + k), ray, k);
        P::occluded(valid, scene, &ctx, &ray);
        for (unsigned k = 0; k < lanes; ++k) hits[first + k] = occlusion_hit(at(first + k), ray.tfar[k]);
      } else {
        for (unsigned k = 0; k < lanes; ++k) {
          set_lane(at(first + k), rh.ray, k);
          rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        P::intersect(valid, scene, &ctx, &rh);
        for (unsigned k = 0; k < lanes; ++k)
          hits[first + k] = closest_hit(at(first + k), rh.ray.tfar[k], rh.hit.geomID[k], rh.hit.primID[k],
                                        rh.hit.u[k], rh.hit.v[k]);
      }
    }
  });
}

}  // namespace

std::string EmbreeScene::version() { return RTC_VERSION_STRING; }

EmbreeScene::EmbreeScene(const Scene::Flat& tris, unsigned threads, const std::string& isa) : isa_(isa) {
  check_embree_isa(isa);
  threads_ = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  const std::string config = fmt::format("threads={}{}", threads_, isa == "native" ? "" : ",isa=" + isa);
  device_ = rtcNewDevice(config.c_str());
  if (!device_) {
    const int code = static_cast<int>(rtcGetDeviceError(nullptr));
    if (code == RTC_ERROR_UNSUPPORTED_CPU)
      throw Error(fmt::format("--embree-isa {}: this CPU does not run it (rtcNewDevice(\"{}\"): RTC_ERROR_UNSUPPORTED_CPU); "
                              "choose a set it runs, or native", isa, config));
    throw Error(fmt::format("rtcNewDevice(\"{}\") failed: {}", config, code));
  }
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
  return trace(rays, any_hit, EmbreePath::Single);
}

std::vector<RsHit> EmbreeScene::trace(const std::vector<RsRay>& rays, bool any_hit, EmbreePath path,
                                      std::span<const std::uint32_t> order) const {
  const std::size_t n = rays.size();
  if (!order.empty()) {
    // Every rays[order[i]] must exist: one pass over the order, before any thread reads a ray.
    if (order.size() != n) throw Error(fmt::format("Embree trace: an order of {} entries for {} rays", order.size(), n));
    const std::uint32_t top = *std::max_element(order.begin(), order.end());
    if (top >= n) throw Error(fmt::format("Embree trace: order entry {} for {} rays", top, n));
  }
  std::vector<RsHit> hits(n);
  const RayAt at{rays.data(), order.empty() ? nullptr : order.data()};
  const EmbreePathInfo& info = embree_path_info(path);
  switch (info.packet) {
    case 0: trace_stream(scene_, at, n, any_hit, info.coherent, threads_, hits.data()); break;
    case 1: trace_single(scene_, at, n, any_hit, info.coherent, threads_, hits.data()); break;
    case 4: trace_packets<4>(scene_, at, n, any_hit, info.coherent, threads_, hits.data()); break;
    case 8: trace_packets<8>(scene_, at, n, any_hit, info.coherent, threads_, hits.data()); break;
    case 16: trace_packets<16>(scene_, at, n, any_hit, info.coherent, threads_, hits.data()); break;
    default: throw Error(fmt::format("Embree path {}: no trace for {} rays per call", info.key, info.packet));
  }
  return hits;
}

bool EmbreeScene::native_packets(unsigned width) const {
  const RTCDeviceProperty property = width == 4   ? RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED
                                     : width == 8 ? RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED
                                                  : RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED;
  return rtcGetDeviceProperty(device_, property) != 0;
}

const EmbreePathInfo& embree_path_info(EmbreePath path) {
  for (const EmbreePathInfo& info : kEmbreePaths)
    if (info.path == path) return info;
  throw Error(fmt::format("Embree path {} is not in kEmbreePaths", static_cast<int>(path)));
}

std::string embree_path_name(EmbreePath path, bool any_hit) {
  const EmbreePathInfo& info = embree_path_info(path);
  const char* call = any_hit ? info.occluded : info.intersect;
  if (path == EmbreePath::Single) return call;
  return fmt::format("{} {}", call, info.coherent ? "coherent" : "incoherent");
}

std::string embree_path_calls(EmbreePath path) {
  return embree_path_name(path, false) + " / " + embree_path_name(path, true);
}

std::vector<EmbreePath> parse_embree_paths(const std::string& list) {
  std::string valid;
  for (const EmbreePathInfo& info : kEmbreePaths) valid += fmt::format("{} ({}), ", info.key, embree_path_name(info.path, false));
  valid += "or all";
  const std::vector<std::string> keys = split_list(list);
  if (keys.empty()) throw Error("--embree-paths: name at least one Embree path: " + valid);
  std::vector<EmbreePath> out;
  for (const std::string& key : keys) {
    if (key == "all") {
      out.clear();
      for (const EmbreePathInfo& info : kEmbreePaths) out.push_back(info.path);
      return out;
    }
    const auto it = std::find_if(std::begin(kEmbreePaths), std::end(kEmbreePaths),
                                 [&](const EmbreePathInfo& info) { return key == info.key; });
    if (it == std::end(kEmbreePaths))
      throw Error(fmt::format("unknown Embree path '{}' in --embree-paths; the paths are {}", key, valid));
    if (std::find(out.begin(), out.end(), it->path) == out.end()) out.push_back(it->path);
  }
  return out;
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

#include "render/pathtrace.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "render/batches.h"
#include "util/error.h"
#include "util/parallel.h"

namespace raysort {

namespace {

void copy3(float* dst, const Vec3& v) { dst[0] = v[0], dst[1] = v[1], dst[2] = v[2]; }

// The pass's parameters: samples [sample_begin, sample_begin + sample_count) of pixels
// [pixel_begin, pixel_begin + pixel_count); `pixels` is set to the pass's pixel count.
RsShadeParams frame_params(const ShadeInputs& in, const FrameOptions& opts, std::uint32_t& pixels) {
  RsShadeParams p = in.params;
  if (opts.sample_begin >= in.spp) throw Error(fmt::format("sample {} is past the frame's {} spp", opts.sample_begin, in.spp));
  const std::uint64_t frame_pixels = std::uint64_t{in.width} * in.height;
  if (opts.pixel_begin >= frame_pixels)
    throw Error(fmt::format("pixel {} is past the frame's {} pixels", opts.pixel_begin, frame_pixels));
  p.sample_begin = opts.sample_begin;
  p.spp = opts.sample_count ? std::min(opts.sample_count, in.spp - opts.sample_begin) : in.spp - opts.sample_begin;
  p.pixel_begin = opts.pixel_begin;
  const std::uint64_t left = frame_pixels - opts.pixel_begin;
  pixels = static_cast<std::uint32_t>(opts.pixel_count ? std::min<std::uint64_t>(opts.pixel_count, left) : left);
  const std::uint64_t paths = std::uint64_t{pixels} * p.spp;
  if (paths * std::max<std::uint64_t>(1, p.shadow_per_hit) >= (std::uint64_t{1} << 32))
    throw Error(fmt::format("{} pixels at {} spp is too many paths for one pass; render fewer pixels or samples per pass",
                            pixels, p.spp));
  return p;
}

RsPathState start_state(std::uint32_t path) {
  RsPathState s;
  s.weight[0] = s.weight[1] = s.weight[2] = 1.0f;
  s.path = path;
  return s;
}

}  // namespace

std::string batch_name(BatchKind kind, std::uint32_t bounce) {
  switch (kind) {
    case BatchKind::Primary: return "primary";
    case BatchKind::Shadow: return "shadow" + std::to_string(bounce);
    case BatchKind::Bounce: return "bounce" + std::to_string(bounce);
  }
  return "?";
}

ShadeInputs make_shade_inputs(const Scene& scene, const Scene::Flat& tris, const RayGenOptions& o) {
  ShadeInputs in;
  // The frame is the scene's: a command's --resolution / --spp were applied when it was loaded
  // (scene/load.h, apply_frame_size).
  in.width = scene.camera.width;
  in.height = scene.camera.height;
  in.spp = scene.effects.samples_per_pixel;
  if (in.spp == 0) throw Error("samples per pixel must be at least 1");
  in.camera = make_camera(scene.camera, in.width, in.height);

  for (const Material& m : scene.materials) {
    RsMaterial r{};
    copy3(r.albedo, m.albedo);
    r.mirror = m.mirror ? 1u : 0u;
    in.materials.push_back(r);
  }
  in.triangles.resize(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    RsShadeTriangle& t = in.triangles[i];
    t = RsShadeTriangle{};
    copy3(t.v0, tris.v0[i]);
    copy3(t.v1, tris.v1[i]);
    copy3(t.v2, tris.v2[i]);
    const std::int32_t m = tris.material.empty() ? 0 : tris.material[i];
    t.material = m >= 0 && static_cast<std::size_t>(m) < in.materials.size() ? static_cast<std::uint32_t>(m) : 0u;
  }

  // Lights: radii resolved against the largest extent (the paper's Table 1), and the cumulative
  // power that next-event estimation picks a light from.
  const float extent = scene.bounds().largest_extent();
  float total = 0.0f;
  for (const SphereLight& l : scene.sphere_lights) {
    total += std::max(0.0f, l.power);
    RsSphereLight r{};
    copy3(r.center, l.center);
    r.radius = l.radius(extent);
    copy3(r.color, l.color);
    r.cdf = total;
    in.lights.push_back(r);
  }

  RsShadeParams& p = in.params;
  p = RsShadeParams{};
  p.sky_enabled = scene.sky.enabled ? 1u : 0u;
  copy3(p.sky_zenith, scene.sky.zenith);
  copy3(p.sky_horizon, scene.sky.horizon);
  p.light_count = static_cast<std::uint32_t>(in.lights.size());
  p.power_total = total;
  p.rr_survival = scene.effects.russian_roulette_survival;
  p.rr_start = scene.effects.russian_roulette_start;
  // No sphere lights: no next-event estimation, so no shadow batches (the sky is reached by misses).
  p.shadow_per_hit = next_event_estimation(scene) ? scene.effects.shadow_rays_per_bounce : 0u;
  if (p.shadow_per_hit > RS_MAX_SHADOW_PER_HIT)
    throw Error(fmt::format("{} shadow rays per bounce is more than the {} supported", p.shadow_per_hit,
                            RS_MAX_SHADOW_PER_HIT));
  p.max_bounces = scene.effects.max_bounces;
  p.seed = o.seed;
  p.spp = in.spp;
  p.sample_begin = 0;
  return in;
}

// ---------------------------------------------------------------------------------------------
// Host twin: the stages as loops, in the order the device runs them.

namespace {

// Stable compaction of the valid slots; dest[slot] = its index among them.
template <class T>
std::vector<T> compact_host(const std::vector<std::uint32_t>& valid, std::vector<std::uint32_t>& dest,
                            const std::vector<T>& in) {
  std::vector<T> out;
  for (std::size_t s = 0; s < valid.size(); ++s)
    if (valid[s]) {
      dest[s] = static_cast<std::uint32_t>(out.size());
      out.push_back(in[s]);
    }
  return out;
}

}  // namespace

Frame trace_frame_host(const ShadeInputs& in, const Bvh& bvh, const FrameOptions& opts, TraceVariant variant) {
  std::uint32_t pixels = 0;
  const RsShadeParams p = frame_params(in, opts, pixels);
  const std::size_t n0 = std::size_t{pixels} * p.spp;
  const std::size_t per = p.shadow_per_hit;
  Frame f;
  f.spp = p.spp;
  f.pixel_begin = p.pixel_begin;
  f.pixels = pixels;
  f.radiance.assign(3 * n0, 0.0f);
  if (opts.count_visits) f.visits.assign(n0, 0);

  // 1. generate
  std::vector<RsRay> rays(n0);
  std::vector<RsPathState> states(n0);
  for (std::size_t i = 0; i < n0; ++i) {
    rays[i] = rs_primary_ray(in.camera, p, static_cast<rs_u32>(i));
    states[i] = start_state(static_cast<std::uint32_t>(i));
  }
  auto emit = [&](BatchKind kind, std::uint32_t bounce, const std::vector<RsRay>& r, const std::vector<RsPathState>& s,
                  const std::vector<RsHit>& h) {
    f.batches.push_back({batch_name(kind, bounce), kind, bounce, r.size()});
    if (opts.sink) opts.sink(TracedBatch{kind, bounce, r, s, h});
  };

  std::vector<RsRay> shadow_rays, bounce_rays;
  std::vector<RsPathState> shadow_states, bounce_states;
  std::vector<std::uint32_t> shadow_valid, shadow_dest, bounce_valid, bounce_dest, visits;
  for (std::uint32_t bounce = 0; !rays.empty(); ++bounce) {
    const std::size_t n = rays.size();
    // 2. trace
    auto hits = trace_reference(bvh, rays, nullptr, false, opts.count_visits ? &visits : nullptr, variant);
    emit(bounce == 0 ? BatchKind::Primary : BatchKind::Bounce, bounce, rays, states, hits);
    if (opts.count_visits)
      for (std::size_t i = 0; i < n; ++i) f.visits[states[i].path] += visits[i];
    // 3. shade
    shadow_rays.resize(n * per), shadow_states.resize(n * per), shadow_valid.resize(n * per), shadow_dest.resize(n * per);
    bounce_rays.resize(n), bounce_states.resize(n), bounce_valid.resize(n), bounce_dest.resize(n);
    // One ray per item, as one per work-item in the shade kernel: a ray writes only its own slots
    // and its own path's radiance, so the blocks may run on any thread.
    for_each_block(n, n < 4096, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        rs_shade(in.triangles.data(), in.materials.data(), in.lights.data(), p, bounce, static_cast<rs_u32>(i), rays[i],
                 states[i], hits[i], f.radiance.data(), shadow_rays.data(), shadow_states.data(), shadow_valid.data(),
                 bounce_rays.data(), bounce_states.data(), bounce_valid.data());
    });
    // 4.-5. compact the shadow rays, trace them (any hit), add what reached a light
    if (per > 0) {
      auto srays = compact_host(shadow_valid, shadow_dest, shadow_rays);
      auto sstates = compact_host(shadow_valid, shadow_dest, shadow_states);
      std::vector<RsHit> shits;
      if (!srays.empty()) {
        shits = trace_reference(bvh, srays, nullptr, true, nullptr, variant);
        emit(BatchKind::Shadow, bounce, srays, sstates, shits);
      }
      for (std::size_t i = 0; i < n; ++i)
        rs_accumulate_shadow(p, static_cast<rs_u32>(i), states[i].path, shadow_valid.data(), shadow_dest.data(),
                             shadow_states.data(), shits.data(), f.radiance.data());
    }
    // 6. the next bounce: terminated paths compacted out
    if (bounce >= p.max_bounces) break;
    rays = compact_host(bounce_valid, bounce_dest, bounce_rays);
    states = compact_host(bounce_valid, bounce_dest, bounce_states);
  }
  return f;
}

// ---------------------------------------------------------------------------------------------
// Device: one kernel per stage (cl/shade.cl); tracing through Tracer.

namespace {
constexpr std::size_t kCompactBlock = 256;  // RS_COMPACT_BLOCK in cl/shade.cl
}

DevicePathTracer::DevicePathTracer(Runtime& rt, const Bvh& bvh, const ShadeInputs& in, TraceVariant variant)
    : rt_(rt), in_(in), tracer_(rt, bvh, variant) {
  triangles_ = rt.upload("shading triangles", in.triangles);
  materials_ = rt.upload("materials", in.materials);
  lights_ = rt.upload("sphere lights", in.lights.empty() ? std::vector<RsSphereLight>(1) : in.lights);
  cl::Program program = rt.build({"cl/shade.cl"});
  cl_call("creating the path tracer kernels", [&] {
    generate_ = cl::Kernel(program, "generate_primary");
    shade_ = cl::Kernel(program, "shade");
    accumulate_ = cl::Kernel(program, "accumulate_shadow");
    visits_ = cl::Kernel(program, "accumulate_visits");
    count_ = cl::Kernel(program, "compact_count");
    scan_ = cl::Kernel(program, "compact_scan");
    dest_ = cl::Kernel(program, "compact_dest");
    copy_ = cl::Kernel(program, "compact_copy");
  });
  local_ = std::min<std::size_t>(64, rt.info().max_work_group_size);
}

void DevicePathTracer::launch(cl::Kernel& k, std::size_t n, const std::string& doing) {
  if (n == 0) return;
  cl_call(doing, [&] {
    rt_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(Runtime::padded(n, local_)), cl::NDRange(local_));
  });
}

std::uint32_t DevicePathTracer::compact(const cl::Buffer& valid, std::uint32_t n, const cl::Buffer& dest,
                                        const cl::Buffer& rays, const cl::Buffer& states, const cl::Buffer& out_rays,
                                        const cl::Buffer& out_states) {
  if (n == 0) return 0;
  const auto blocks = static_cast<std::uint32_t>((n + kCompactBlock - 1) / kCompactBlock);
  cl::Buffer block_counts = rt_.buffer("compaction block counts", blocks * sizeof(std::uint32_t));
  cl::Buffer total = rt_.buffer("compaction total", sizeof(std::uint32_t));
  cl_call("setting the compaction arguments", [&] {
    count_.setArg(0, valid), count_.setArg(1, n), count_.setArg(2, block_counts), count_.setArg(3, blocks);
    scan_.setArg(0, block_counts), scan_.setArg(1, blocks), scan_.setArg(2, total);
    dest_.setArg(0, valid), dest_.setArg(1, n), dest_.setArg(2, block_counts), dest_.setArg(3, blocks);
    dest_.setArg(4, dest);
    copy_.setArg(0, valid), copy_.setArg(1, dest), copy_.setArg(2, n), copy_.setArg(3, rays), copy_.setArg(4, states);
    copy_.setArg(5, out_rays), copy_.setArg(6, out_states);
  });
  launch(count_, blocks, "counting valid slots");
  launch(scan_, 1, "scanning block counts");
  launch(dest_, blocks, "placing valid slots");
  launch(copy_, n, "compacting rays");
  std::vector<std::uint32_t> count;
  rt_.download("compaction total", total, count, 1);
  return count[0];
}

Frame DevicePathTracer::trace_frame(const FrameOptions& opts) {
  std::uint32_t pixels = 0;
  const RsShadeParams p = frame_params(in_, opts, pixels);
  const std::size_t n0 = std::size_t{pixels} * p.spp;
  const std::size_t per = p.shadow_per_hit, ns = n0 * per;
  Frame f;
  f.spp = p.spp;
  f.pixel_begin = p.pixel_begin;
  f.pixels = pixels;
  auto buf = [&](const char* name, std::size_t bytes) { return rt_.buffer(name, std::max<std::size_t>(16, bytes)); };
  cl::Buffer params = rt_.upload("shading parameters", std::vector<RsShadeParams>{p});
  std::vector<std::uint32_t> identity(std::max(n0, ns));
  std::iota(identity.begin(), identity.end(), 0u);
  cl::Buffer order = rt_.upload("identity order", identity);
  cl::Buffer rays[2] = {buf("path rays", n0 * sizeof(RsRay)), buf("path rays", n0 * sizeof(RsRay))};
  cl::Buffer states[2] = {buf("path states", n0 * sizeof(RsPathState)), buf("path states", n0 * sizeof(RsPathState))};
  cl::Buffer hits = buf("hits", n0 * sizeof(RsHit)), visits = buf("node visits", n0 * 4);
  cl::Buffer radiance = buf("radiance", 3 * n0 * sizeof(float)), path_visits = buf("path visits", n0 * 4);
  cl::Buffer bounce_rays = buf("bounce slots", n0 * sizeof(RsRay)),
             bounce_states = buf("bounce slot states", n0 * sizeof(RsPathState)),
             bounce_valid = buf("bounce slot flags", n0 * 4), bounce_dest = buf("bounce slot places", n0 * 4);
  cl::Buffer shadow_rays = buf("shadow slots", ns * sizeof(RsRay)),
             shadow_states = buf("shadow slot states", ns * sizeof(RsPathState)),
             shadow_valid = buf("shadow slot flags", ns * 4), shadow_dest = buf("shadow slot places", ns * 4),
             shadow_batch = buf("shadow rays", ns * sizeof(RsRay)),
             shadow_batch_states = buf("shadow ray states", ns * sizeof(RsPathState)),
             shadow_hits = buf("shadow hits", ns * sizeof(RsHit));
  rt_.zero("radiance", radiance, std::max<std::size_t>(16, 3 * n0 * sizeof(float)));
  rt_.zero("path visits", path_visits, std::max<std::size_t>(16, n0 * 4));

  // A batch for the sink, read back from the device (only when someone listens).
  auto emit = [&](BatchKind kind, std::uint32_t bounce, std::size_t n, const cl::Buffer& r, const cl::Buffer& s,
                  const cl::Buffer& h) {
    f.batches.push_back({batch_name(kind, bounce), kind, bounce, n});
    if (!opts.sink) return;
    std::vector<RsRay> hr;
    std::vector<RsPathState> hs;
    std::vector<RsHit> hh;
    rt_.download("batch rays", r, hr, n);
    rt_.download("batch states", s, hs, n);
    rt_.download("batch hits", h, hh, n);
    opts.sink(TracedBatch{kind, bounce, hr, hs, hh});
  };

  // 1. generate
  cl_call("setting the generate arguments", [&] {
    generate_.setArg(0, in_.camera), generate_.setArg(1, params), generate_.setArg(2, static_cast<cl_uint>(n0));
    generate_.setArg(3, rays[0]), generate_.setArg(4, states[0]);
  });
  launch(generate_, n0, "generating primary rays");

  int cur = 0;
  auto n = static_cast<std::uint32_t>(n0);
  for (std::uint32_t bounce = 0; n > 0; ++bounce) {
    // 2. trace
    if (opts.count_visits) {
      tracer_.enqueue_counted(rays[cur], order, n, hits, visits);
      cl_call("setting the visit arguments", [&] {
        visits_.setArg(0, n), visits_.setArg(1, states[cur]), visits_.setArg(2, visits), visits_.setArg(3, path_visits);
      });
      launch(visits_, n, "adding node visits");
    } else {
      tracer_.enqueue(rays[cur], order, n, false, hits);
    }
    emit(bounce == 0 ? BatchKind::Primary : BatchKind::Bounce, bounce, n, rays[cur], states[cur], hits);
    // 3. shade
    cl_call("setting the shade arguments", [&] {
      const cl::Buffer* args[] = {&triangles_, &materials_, &lights_, &params};
      for (int a = 0; a < 4; ++a) shade_.setArg(a, *args[a]);
      shade_.setArg(4, bounce), shade_.setArg(5, n), shade_.setArg(6, rays[cur]), shade_.setArg(7, states[cur]);
      shade_.setArg(8, hits), shade_.setArg(9, radiance), shade_.setArg(10, shadow_rays);
      shade_.setArg(11, shadow_states), shade_.setArg(12, shadow_valid), shade_.setArg(13, bounce_rays);
      shade_.setArg(14, bounce_states), shade_.setArg(15, bounce_valid);
    });
    launch(shade_, n, "shading hits");
    // 4.-5. shadow rays: compact, trace (any hit), accumulate
    if (per > 0) {
      const std::uint32_t m = compact(shadow_valid, static_cast<std::uint32_t>(n * per), shadow_dest, shadow_rays,
                                      shadow_states, shadow_batch, shadow_batch_states);
      if (m > 0) {
        tracer_.enqueue(shadow_batch, order, m, true, shadow_hits);
        emit(BatchKind::Shadow, bounce, m, shadow_batch, shadow_batch_states, shadow_hits);
      }
      cl_call("setting the accumulate arguments", [&] {
        accumulate_.setArg(0, params), accumulate_.setArg(1, n), accumulate_.setArg(2, states[cur]);
        accumulate_.setArg(3, shadow_valid), accumulate_.setArg(4, shadow_dest), accumulate_.setArg(5, shadow_states);
        accumulate_.setArg(6, shadow_hits), accumulate_.setArg(7, radiance);
      });
      launch(accumulate_, n, "adding unoccluded light");
    }
    // 6. the next bounce: terminated paths compacted out
    if (bounce >= p.max_bounces) break;
    n = compact(bounce_valid, n, bounce_dest, bounce_rays, bounce_states, rays[1 - cur], states[1 - cur]);
    cur = 1 - cur;
  }
  rt_.download("radiance", radiance, f.radiance, 3 * n0);
  if (opts.count_visits) rt_.download("path visits", path_visits, f.visits, n0);
  return f;
}

// ---------------------------------------------------------------------------------------------

std::vector<std::string> describe_stages(const Scene& scene) {
  const Effects& e = scene.effects;
  const bool nee = next_event_estimation(scene);
  bool mirror = false, diffuse = false;
  for (const Material& m : scene.materials) (m.mirror ? mirror : diffuse) = true;
  std::vector<std::string> out;
  out.push_back("generate   primary rays, one per pixel and sample, jittered within the pixel");
  out.push_back("trace      closest hit");
  std::string sky = !scene.sky.enabled ? "none: a miss ends the path dark"
                    : scene.sky.zenith == scene.sky.horizon ? "constant sky added on a miss"
                                                            : "gradient sky (horizon to zenith) added on a miss";
  out.push_back("shade      " + sky);
  if (nee)
    out.push_back(fmt::format("           next-event estimation: {} shadow ray{} per diffuse hit toward {} sphere light{}, "
                              "light chosen by power",
                              e.shadow_rays_per_bounce, e.shadow_rays_per_bounce == 1 ? "" : "s",
                              scene.sphere_lights.size(), scene.sphere_lights.size() == 1 ? "" : "s"));
  else
    out.push_back(std::string("           no next-event estimation (") +
                  (scene.sphere_lights.empty() ? "no sphere lights" : "shadow_rays_per_bounce = 0") + ")");
  if (e.max_bounces > 0) {
    std::string kinds = std::string(diffuse ? "diffuse (cosine-weighted)" : "") + (diffuse && mirror ? " and " : "") +
                        (mirror ? "mirror" : "");
    std::string rr = e.russian_roulette_start <= e.max_bounces
                         ? fmt::format("; Russian roulette from bounce {} (survival {})",
                                       std::max<std::uint32_t>(1, e.russian_roulette_start), e.russian_roulette_survival)
                         : "; no Russian roulette (it starts past the last bounce)";
    out.push_back(fmt::format("           next bounce: {} up to bounce {}{}", kinds, e.max_bounces, rr));
  } else {
    out.push_back("           no bounces (max_bounces = 0)");
  }
  if (nee) out.push_back("compact    valid shadow slots -> shadow<k>; trace any hit; accumulate unoccluded light");
  if (e.max_bounces > 0) out.push_back("compact    surviving paths -> bounce<k+1>; repeat from trace");
  return out;
}

}  // namespace raysort

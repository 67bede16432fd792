#include "sort/radix_sort.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>

namespace raysort {

namespace {

unsigned floor_pow2(std::size_t v) {
  unsigned p = 1;
  while (p * 2 <= v && p < (1u << 30)) p *= 2;
  return p;
}

std::string program_options(const RadixSortTuning& t, unsigned key_bits) {
  return fmt::format("-DRS_KEY_BITS={} -DRS_RADIX_BITS={} -DRS_WG={} -DRS_MAX_ITEMS={} -DRS_SCAN_WG={}", key_bits,
                     t.radix_bits, t.work_group, t.items, t.scan_work_group);
}

}  // namespace

std::size_t RadixSortTuning::local_bytes(std::size_t key_bytes) const {
  const std::size_t radix = std::size_t(1) << radix_bits;
  const std::size_t count = radix * 4 + 2 * std::size_t(work_group) * key_bytes;
  if (work_group == 1) {
    if (!hybrid()) return count;
    return std::max<std::size_t>(count, max_passes(key_bytes * 8) * radix * 4);  // rs_bucket_sort's histograms
  }
  std::size_t scatter =
      std::size_t(work_group) * items * (key_bytes + 4) + radix * work_group * 4 + work_group * 4 + radix * 4;
  if (!onesweep) return std::max(count, scatter);
  scatter += radix * 4 + 4;  // rs_onesweep: the tile's digit counts and its index
  return std::max({count, scatter, max_passes(key_bytes * 8) * radix * 4});  // rs_hist_all: every pass's histogram
}

RadixSortTuning RadixSortTuning::for_device(const DeviceInfo& device) {
  RadixSortTuning t;
  if (device.type != "GPU") {
    // A CPU (PoCL): a work-item is a scalar loop and local memory is ordinary memory, so one
    // work-item per tile scatters its chunk serially; 8-bit digits keep the 2 x 256 output
    // streams of a tile (keys, values) within the L1/L2 caches.
    t.radix_bits = 8;
    t.work_group = 1;
    t.scan_work_group = 1;
    t.reduce_work_group = 64;
    return t;
  }
  // A GPU: the widest digit (8 down to 4 bits) whose [digit][work-item] rank table plus a staged
  // tile of 64-bit keys fits the device's local memory with at least 128 work-items per group.
  const std::size_t max_wg = std::max<std::size_t>(1, device.max_work_group_size);
  const unsigned min_wg = std::min<unsigned>(128, floor_pow2(max_wg));
  t.items = 8;
  t.radix_bits = 0;
  for (unsigned bits = 8; bits >= 4 && t.radix_bits == 0; --bits) {
    for (unsigned wg = std::min<unsigned>(256, floor_pow2(max_wg)); wg >= min_wg; wg /= 2) {
      RadixSortTuning c = t;
      c.radix_bits = bits;
      c.work_group = wg;
      if (c.local_bytes(8) <= device.local_mem_bytes) {
        t = c;
        break;
      }
    }
  }
  if (t.radix_bits == 0) {  // a tiny local memory: the smallest shape that fits
    t.radix_bits = 4;
    t.work_group = min_wg;
    while (t.work_group > 1 && t.local_bytes(8) > device.local_mem_bytes) t.work_group /= 2;
  }
  t.scan_work_group = std::min<unsigned>(1024, floor_pow2(max_wg));
  t.reduce_work_group = std::min<unsigned>(64, floor_pow2(max_wg));
  // Onesweep's look-back spins on other work-groups' progress: on NVIDIA's GPUs a started
  // work-group keeps running; elsewhere nothing here has shown it does (issue 42, item 1).
  t.onesweep = device.platform_name.find("NVIDIA") != std::string::npos;
  if (t.onesweep && t.local_bytes(8) > device.local_mem_bytes) t.onesweep = false;
  return t;
}

RadixSort::RadixSort(Runtime& rt)
    : RadixSort(rt, RadixSortTuning::for_device(rt.info()), RadixSortFit::ShrinkToKernels) {}

RadixSort::RadixSort(Runtime& rt, const RadixSortTuning& tuning, RadixSortFit fit) : rt_(rt), tuning_(tuning) {
  auto pow2 = [](unsigned v) { return v >= 1 && (v & (v - 1)) == 0; };
  if (tuning_.radix_bits < 1 || tuning_.radix_bits > 12 || !pow2(tuning_.work_group) || tuning_.items < 1 ||
      !pow2(tuning_.scan_work_group) || tuning_.reduce_work_group < 1 || tuning_.hybrid_skew < 1)
    throw Error(fmt::format("radix sort: invalid tuning (radix_bits {}, work_group {}, items {}, scan_work_group {})",
                            tuning_.radix_bits, tuning_.work_group, tuning_.items, tuning_.scan_work_group));
  if (tuning_.onesweep && tuning_.work_group == 1)
    throw Error("radix sort: Onesweep needs the GPU shape (a work-group of more than one work-item per tile); "
                "force a work-group of 2 or more, or leave Onesweep off");
  if (tuning_.local_bytes(8) > rt.info().local_mem_bytes)
    throw Error(fmt::format("radix sort: the tuning needs {} of local memory, device '{}' has {}",
                            human_bytes(tuning_.local_bytes(8)), rt.info().name,
                            human_bytes(rt.info().local_mem_bytes)));
  // A device's maximum work-group size is not every kernel's: NVIDIA's H200 takes 1024 work-items
  // per group but rs_scan only 256 (its registers). The device's own shape shrinks the launch that
  // does not fit and builds again (the sorted result does not depend on the shape); a forced shape
  // is refused instead, naming the most the kernel takes.
  for (;;) {
    const std::optional<KernelOverflow> over = build_kernels(rt);
    if (!over) break;
    if (fit == RadixSortFit::Exact)
      throw Error(fmt::format("radix sort: a work-group of {} work-items (work_group {}, scan_work_group {}) is more "
                              "than kernel {} takes on device '{}' ({}); force {} or fewer",
                              over->local, tuning_.work_group, tuning_.scan_work_group, over->name, rt.info().name,
                              over->most, over->most));
    (over->scan_shape ? tuning_.scan_work_group : tuning_.work_group) = floor_pow2(over->most);  // < the launch
  }
}

std::optional<RadixSort::KernelOverflow> RadixSort::build_kernels(Runtime& rt) {
  for (unsigned key_bits : {32u, 64u}) {
    cl::Program program = rt.build({"cl/radix_sort.cl"}, program_options(tuning_, key_bits));
    Kernels& k = key_bits == 64 ? wide_ : narrow_;
    cl_call("creating the radix sort kernels", [&] {
      k.count_bounds = cl::Kernel(program, "rs_count_bounds");
      k.reduce_bounds = cl::Kernel(program, "rs_reduce_bounds");
      k.count = cl::Kernel(program, "rs_count");
      k.scan = cl::Kernel(program, "rs_scan");
      k.scatter = cl::Kernel(program, "rs_scatter");
      if (tuning_.hybrid()) k.bucket_sort = cl::Kernel(program, "rs_bucket_sort");
      if (warp_sort_shape()) k.warp_sort = cl::Kernel(program, "rs_warp_sort");
      if (tuning_.onesweep) {
        k.sweep_clear = cl::Kernel(program, "rs_sweep_clear");
        k.hist_all = cl::Kernel(program, "rs_hist_all");
        k.hist_scan = cl::Kernel(program, "rs_hist_scan");
        k.onesweep = cl::Kernel(program, "rs_onesweep");
      }
    });
    // Every launch's work-group must fit what the kernel takes on this device: a launch over it
    // fails with CL_INVALID_WORK_GROUP_SIZE in the middle of a sort, and PoCL then aborted the
    // process at exit (sortcheck --scan-work-group 8192).
    struct Launch {
      cl::Kernel* kernel;
      const char* name;
      unsigned local;
      bool scan_shape;
    };
    std::vector<Launch> launches = {{&k.count_bounds, "rs_count_bounds", tuning_.work_group, false},
                                    {&k.count, "rs_count", tuning_.work_group, false},
                                    {&k.scatter, "rs_scatter", tuning_.work_group, false},
                                    {&k.scan, "rs_scan", tuning_.scan_work_group, true},
                                    {&k.reduce_bounds, "rs_reduce_bounds", tuning_.scan_work_group, true}};
    if (tuning_.onesweep)
      launches.insert(launches.end(), {{&k.sweep_clear, "rs_sweep_clear", tuning_.work_group, false},
                                       {&k.hist_all, "rs_hist_all", tuning_.work_group, false},
                                       {&k.onesweep, "rs_onesweep", tuning_.work_group, false},
                                       {&k.hist_scan, "rs_hist_scan", tuning_.scan_work_group, true}});
    for (const Launch& l : launches) {
      const std::size_t most = cl_call("querying a radix sort kernel's work-group size", [&] {
        return l.kernel->getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(rt.info().device);
      });
      if (l.local > most) return KernelOverflow{l.name, l.local, most, l.scan_shape};
    }
  }
  return std::nullopt;
}

unsigned RadixSort::passes(const RadixSortConfig& cfg) const {
  return tuning_.max_passes(cfg.sorted_bits());
}

void RadixSort::ensure(Runtime& rt, cl::Buffer& b, std::size_t& have, std::size_t need, const char* name) {
  if (need <= have && have > 0) return;
  b = cl::Buffer();  // release before allocating the larger one
  have = 0;
  b = rt.buffer(name, std::max<std::size_t>(need, 4));
  have = std::max<std::size_t>(need, 4);
}

cl::Event& RadixSort::record(const char* name) {
  events_.emplace_back();
  event_names_.push_back(name);
  return events_.back();
}

void RadixSort::enqueue(cl::Kernel& k, const char* name, std::size_t global, std::size_t local) {
  rt_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(Runtime::padded(global, local)), cl::NDRange(local),
                                   nullptr, &record(name));
}

namespace {

// Sets a kernel's arguments 0, 1, ... in order.
template <class... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  cl_uint index = 0;
  (kernel.setArg(index++, args), ...);
}

}  // namespace

// One sort's passes: the kernels' arguments, which buffers hold the pairs now (ping-pong between
// the caller's and the scratch buffers), and the launches of each kind of pass.
struct RadixSort::Passes {
  RadixSort& rs;
  Kernels& k;
  const cl_uint n, n_items, hi;
  const std::size_t wg, tiles, bins;
  SortStats& stats;
  cl::Buffer *src_keys, *src_values, *dst_keys, *dst_values;

  void count(cl_uint shift) {
    set_args(k.count, *src_keys, n, n_items, shift, hi, rs.counts_);
    rs.enqueue(k.count, "rs_count", tiles * wg, wg);
  }
  void scan() {
    set_args(k.scan, rs.counts_, static_cast<cl_uint>(bins));
    rs.enqueue(k.scan, "rs_scan", rs.tuning_.scan_work_group, rs.tuning_.scan_work_group);
  }
  void flip() {
    std::swap(src_keys, dst_keys);
    std::swap(src_values, dst_values);
    ++stats.passes_run;
  }
  void scatter(cl_uint shift) {
    set_args(k.scatter, *src_keys, *src_values, *dst_keys, *dst_values, n, n_items, shift, hi, rs.counts_);
    rs.enqueue(k.scatter, "rs_scatter", tiles * wg, wg);
    flip();
  }
  // The hybrid's LSD passes over the lower digits `pass_mask`, one work-item per top-digit bucket.
  void bucket_sort(cl_uint lo, cl_uint pass_mask, std::size_t radix) {
    set_args(k.bucket_sort, *src_keys, *src_values, *dst_keys, *dst_values, n, static_cast<cl_uint>(tiles), rs.counts_,
             lo, hi, pass_mask);
    rs.enqueue(k.bucket_sort, "rs_bucket_sort", radix, 1);
  }
  // The warp-granular sort's walk of every top-digit bucket (pass_mask: the varying 8-bit digits).
  void warp_sort(cl_uint lo, cl_uint top_pass, cl_uint pass_mask, cl_uint group, std::size_t radix) {
    set_args(k.warp_sort, *src_keys, *src_values, *dst_keys, *dst_values, n, static_cast<cl_uint>(tiles), rs.counts_,
             lo, hi, top_pass, pass_mask, group);
    rs.enqueue(k.warp_sort, "rs_warp_sort", radix, 1);
    flip();  // every bucket's result lies in the destination buffers
  }
};

// The first read of the keys: the tile counts of digit `shift`, and which key bits vary at all
// (the OR and AND of every key, read back: 16 bytes).
std::uint64_t RadixSort::first_read(Kernels& k, const cl::Buffer& keys, cl_uint n, cl_uint n_items, cl_uint shift,
                                    cl_uint hi, std::size_t tiles, std::size_t key_bytes) {
  std::uint64_t varying = 0;
  cl_call("running the radix sort's first read", [&] {
    k.count_bounds.setArg(0, keys);
    k.count_bounds.setArg(1, n);
    k.count_bounds.setArg(2, n_items);
    k.count_bounds.setArg(3, shift);
    k.count_bounds.setArg(4, hi);
    k.count_bounds.setArg(5, counts_);
    k.count_bounds.setArg(6, tile_bounds_);
    enqueue(k.count_bounds, "rs_count_bounds", tiles * tuning_.work_group, tuning_.work_group);
    k.reduce_bounds.setArg(0, tile_bounds_);
    k.reduce_bounds.setArg(1, static_cast<cl_uint>(tiles));
    k.reduce_bounds.setArg(2, bounds_);
    enqueue(k.reduce_bounds, "rs_reduce_bounds", tuning_.scan_work_group, tuning_.scan_work_group);
    std::uint64_t bounds[2] = {0, 0};  // OR, AND of all keys
    rt_.queue().enqueueReadBuffer(bounds_, CL_TRUE, 0, 2 * key_bytes, bounds, nullptr, &record("read key bounds"));
    if (key_bytes == 4) {
      std::uint32_t b32[2];
      std::memcpy(b32, bounds, sizeof b32);
      bounds[0] = b32[0];
      bounds[1] = b32[1];
    }
    varying = bounds[0] ^ bounds[1];
  });
  return varying;
}

// The MSD-first hybrid: bucket by the highest varying digit, then sort each bucket by the lower
// digits while it sits in cache. False (nothing moved) when one bucket would hold more than
// 1 / hybrid_skew of the pairs; the LSD passes then do the whole sort.
bool RadixSort::hybrid_passes(Passes& ps, const std::vector<unsigned>& run, int counted, cl_uint lo,
                              std::size_t count) {
  const RadixSortTuning& t = tuning_;
  const std::size_t radix = std::size_t(1) << t.radix_bits;
  const unsigned top = run.back();
  const cl_uint top_shift = lo + top * t.radix_bits;
  if (static_cast<int>(top) != counted) ps.count(top_shift);
  ps.scan();
  bucket_offsets_.resize(ps.bins);  // the scanned counts: bucket d starts at [d * tiles]
  rt_.queue().enqueueReadBuffer(counts_, CL_TRUE, 0, ps.bins * 4, bucket_offsets_.data(), nullptr,
                                &record("read bucket offsets"));
  std::size_t largest = 0;
  for (std::size_t d = 0; d < radix; ++d) {
    const std::size_t end = d + 1 < radix ? bucket_offsets_[(d + 1) * ps.tiles] : count;
    largest = std::max<std::size_t>(largest, end - bucket_offsets_[d * ps.tiles]);
  }
  if (largest * t.hybrid_skew > count) return false;
  ps.scatter(top_shift);  // keys -> scratch, bucketed stably by the top digit
  cl_uint pass_mask = 0;
  for (std::size_t i = 0; i + 1 < run.size(); ++i) pass_mask |= cl_uint(1) << run[i];
  ps.bucket_sort(lo, pass_mask, radix);
  for (std::size_t i = 0; i + 1 < run.size(); ++i) ps.flip();  // the result lies where these passes leave it
  return true;
}

// The warp-granular sort (cfg.warp_group > 0): one global stable pass on the top varying digit,
// then every bucket walked depth first by rs_warp_sort, which leaves the result in the buffers the
// pass read from. Two passes run, whatever the depth of the walk.
void RadixSort::warp_passes(Passes& ps, const std::vector<unsigned>& run, int counted, cl_uint lo, unsigned group) {
  if (run.empty()) return;  // every key the same: the input order is the order
  const unsigned top = run.back();
  const cl_uint top_shift = lo + top * tuning_.radix_bits;
  if (static_cast<int>(top) != counted) ps.count(top_shift);
  ps.scan();
  ps.scatter(top_shift);  // keys -> scratch, bucketed stably by the top digit
  cl_uint pass_mask = 0;
  for (unsigned p : run) pass_mask |= cl_uint(1) << p;
  ps.warp_sort(lo, top, pass_mask, group, std::size_t(1) << tuning_.radix_bits);
}

// Onesweep (tuning.onesweep; cl/radix_sort.cl says how): one read for the digit counts of every
// pass that runs, their scan, then per pass its tile counter and status table zeroed and one
// kernel. The status table is as large as the reduce-then-scan passes' tile counts (counts_).
void RadixSort::onesweep_passes(Passes& ps, const std::vector<unsigned>& run, cl_uint lo, unsigned key_width) {
  const std::size_t radix = std::size_t(1) << tuning_.radix_bits;
  const cl_uint counter = static_cast<cl_uint>(tuning_.max_passes(key_width) * radix), status = counter + 1;
  const cl_uint words = status + static_cast<cl_uint>(ps.bins);
  ensure(rt_, sweep_, sweep_bytes_, std::size_t(words) * 4, "radix sort onesweep status");
  auto clear = [&](cl_uint first) {
    set_args(ps.k.sweep_clear, sweep_, first, words);
    enqueue(ps.k.sweep_clear, "rs_sweep_clear", std::min<std::size_t>(words - first, ps.tiles * ps.wg), ps.wg);
  };
  clear(0);
  cl_uint pass_mask = 0;
  for (unsigned p : run) pass_mask |= cl_uint(1) << p;
  set_args(ps.k.hist_all, *ps.src_keys, ps.n, ps.n_items, lo, ps.hi, pass_mask, sweep_);
  enqueue(ps.k.hist_all, "rs_hist_all", ps.tiles * ps.wg, ps.wg);
  set_args(ps.k.hist_scan, sweep_);
  enqueue(ps.k.hist_scan, "rs_hist_scan", tuning_.scan_work_group, tuning_.scan_work_group);
  for (std::size_t i = 0; i < run.size(); ++i) {
    if (i > 0) clear(counter);
    const cl_uint shift = lo + run[i] * tuning_.radix_bits;
    set_args(ps.k.onesweep, *ps.src_keys, *ps.src_values, *ps.dst_keys, *ps.dst_values, ps.n, ps.n_items, shift, ps.hi,
             sweep_, static_cast<cl_uint>(run[i] * radix), counter, status);
    enqueue(ps.k.onesweep, "rs_onesweep", ps.tiles * ps.wg, ps.wg);
    ps.flip();
  }
}

SortStats RadixSort::sort(cl::Buffer& keys, cl::Buffer& values, std::size_t count, const RadixSortConfig& cfg) {
  if (cfg.key_bits < 1 || cfg.key_bits > 64 || cfg.top_bits > cfg.key_bits)
    throw Error(fmt::format("radix sort: key_bits must be 1..64 and top_bits 0..key_bits (got key_bits {}, top_bits {})",
                            cfg.key_bits, cfg.top_bits));
  if (cfg.warp_group > 0 && !warp_sort_shape())
    throw Error(fmt::format("radix sort: the sort that stops at groups of {} pairs needs the CPU shape (one work-item "
                            "per tile, 8-bit digits); this device's shape has {} work-items per tile and {}-bit digits: "
                            "run it on a CPU device, or without the warp-granular sort",
                            cfg.warp_group, tuning_.work_group, tuning_.radix_bits));
  SortStats stats;
  stats.count = count;
  const unsigned total_passes = passes(cfg);
  if (count < 2 || count <= cfg.warp_group) {  // nothing to order, or one group that keeps its input order
    stats.passes_skipped = total_passes;
    return stats;
  }
  if (count > std::numeric_limits<cl_uint>::max() / 2)
    throw Error(fmt::format("radix sort: {} pairs is more than the 32-bit positions of the kernels can address", count));
  const std::size_t key_bytes = cfg.key_bytes();
  const std::size_t keys_size = cl_call("querying the key buffer's size", [&] { return keys.getInfo<CL_MEM_SIZE>(); });
  const std::size_t values_size =
      cl_call("querying the value buffer's size", [&] { return values.getInfo<CL_MEM_SIZE>(); });
  if (keys_size < count * key_bytes || values_size < count * 4)
    throw Error(fmt::format("radix sort of {} pairs with {}-byte keys: the key buffer holds {} bytes and the value "
                            "buffer {} bytes; they need {} and {}",
                            count, key_bytes, keys_size, values_size, count * key_bytes, count * 4));

  // The shape: a tile is items × work_group keys; on the CPU shape a tile's size follows N.
  const RadixSortTuning& t = tuning_;
  const std::size_t wg = t.work_group;
  std::size_t items = t.items;
  if (wg == 1) {
    const std::size_t target_tiles = std::max<std::size_t>(1, std::size_t(rt_.info().compute_units) * t.tiles_per_unit);
    items = std::max<std::size_t>(t.min_tile, (count + target_tiles - 1) / target_tiles);
  }
  const std::size_t tiles = (count + items * wg - 1) / (items * wg);
  const std::size_t bins = (std::size_t(1) << t.radix_bits) * tiles;
  ensure(rt_, keys_tmp_, keys_tmp_bytes_, count * key_bytes, "radix sort scratch keys");
  ensure(rt_, values_tmp_, values_tmp_bytes_, count * 4, "radix sort scratch values");
  ensure(rt_, counts_, counts_bytes_, bins * 4, "radix sort tile counts");
  ensure(rt_, tile_bounds_, tile_bounds_bytes_, 2 * tiles * key_bytes, "radix sort tile key bounds");
  ensure(rt_, bounds_, bounds_bytes_, 2 * 8, "radix sort key bounds");

  Kernels& k = kernels_for(cfg);
  const cl_uint n = static_cast<cl_uint>(count), n_items = static_cast<cl_uint>(items);
  const cl_uint lo = cfg.lo_bit(), hi = cfg.key_bits;
  events_.clear();
  event_names_.clear();
  // The MSD-first hybrid (large N on the CPU shape) wants the most significant digit's counts
  // first; the plain LSD passes the lowest digit's.
  const bool hybrid = t.hybrid() && count >= t.hybrid_min && total_passes >= 2;
  const bool warp = cfg.warp_group > 0;
  // the pass whose counts are in counts_
  int counted = hybrid || warp ? static_cast<int>(total_passes) - 1 : 0;
  const std::uint64_t varying = first_read(k, keys, n, n_items, lo + counted * t.radix_bits, hi, tiles, key_bytes);
  std::vector<unsigned> run;  // the passes that move keys
  for (unsigned p = 0; p < total_passes; ++p) {
    const unsigned shift = lo + p * t.radix_bits;
    const unsigned width = std::min<unsigned>(t.radix_bits, hi - shift);
    if (((varying >> shift) & ((std::uint64_t(1) << width) - 1)) != 0) run.push_back(p);
  }
  stats.passes_skipped = total_passes - static_cast<unsigned>(run.size());  // same digit in every key

  Passes ps{*this, k, n, n_items, hi, wg, tiles, bins, stats, &keys, &values, &keys_tmp_, &values_tmp_};
  cl_call("running the radix sort passes", [&] {
    bool done = false;
    // Onesweep's status words hold 30-bit counts.
    if (t.onesweep && !warp && !run.empty() && count < (std::size_t(1) << 30)) {
      onesweep_passes(ps, run, lo, cfg.wide_keys() ? 64 : 32);
      done = true;
    } else if (warp) {
      warp_passes(ps, run, counted, lo, cfg.warp_group);
      done = true;
    } else if (hybrid && run.size() >= 2) {
      done = hybrid_passes(ps, run, counted, lo, count);
      counted = -1;  // scanned by the hybrid's check: no pass can use these counts as they are
    }
    if (!done) {
      for (unsigned p : run) {
        const cl_uint shift = lo + p * t.radix_bits;
        if (static_cast<int>(p) != counted) ps.count(shift);  // each pass counts its own digit
        counted = -1;  // ... except a first pass the first read counted
        ps.scan();
        ps.scatter(shift);
      }
    }
    if (stats.passes_run % 2 == 1) {  // the result is in the scratch buffers: copy it home
      rt_.queue().enqueueCopyBuffer(keys_tmp_, keys, 0, 0, count * key_bytes, nullptr, &record("copy result home"));
      rt_.queue().enqueueCopyBuffer(values_tmp_, values, 0, 0, count * 4, nullptr, &record("copy result home"));
    }
    events_.back().wait();
  });
  cl_call("reading the radix sort's profiling events", [&] {
    stats.ms = event_span_ms(events_.front(), events_.back());
    for (std::size_t i = 0; i < events_.size(); ++i) {
      const double ms = event_ms(events_[i]);
      stats.kernel_ms += ms;
      auto same = [&](const SortCommandTime& c) { return c.name == event_names_[i]; };
      auto it = std::find_if(stats.commands.begin(), stats.commands.end(), same);
      if (it == stats.commands.end()) it = stats.commands.insert(it, SortCommandTime{event_names_[i], 0, 0.0});
      it->launches += 1;
      it->ms += ms;
    }
  });
  return stats;
}

template <class Key>
SortStats RadixSort::sort_host(std::vector<Key>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg) {
  if (keys.size() != values.size())
    throw Error(fmt::format("radix sort: {} keys but {} values", keys.size(), values.size()));
  if (cfg.key_bytes() != sizeof(Key))
    throw Error(fmt::format("radix sort: key_bits {} needs {}-byte keys, got {}-byte keys", cfg.key_bits,
                            cfg.key_bytes(), sizeof(Key)));
  const std::size_t n = keys.size();
  if (n == 0) return sort(keys_io_, values_io_, 0, cfg);
  ensure(rt_, keys_io_, keys_io_bytes_, n * sizeof(Key), "radix sort input keys");
  ensure(rt_, values_io_, values_io_bytes_, n * 4, "radix sort input values");
  cl_call("uploading keys and values to sort", [&] {
    rt_.queue().enqueueWriteBuffer(keys_io_, CL_FALSE, 0, n * sizeof(Key), keys.data());
    rt_.queue().enqueueWriteBuffer(values_io_, CL_FALSE, 0, n * 4, values.data());
  });
  SortStats stats = sort(keys_io_, values_io_, n, cfg);
  rt_.download("sorted keys", keys_io_, keys, n);
  rt_.download("sorted values", values_io_, values, n);
  return stats;
}

SortStats RadixSort::sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values,
                          const RadixSortConfig& cfg) {
  return sort_host(keys, values, cfg);
}

SortStats RadixSort::sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values,
                          const RadixSortConfig& cfg) {
  return sort_host(keys, values, cfg);
}

double RadixSort::warm_up() {
  auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = 3 * std::size_t(std::max(tuning_.min_tile, tuning_.items * tuning_.work_group)) + 1;
  std::vector<std::uint32_t> values(n);
  std::iota(values.begin(), values.end(), 0u);
  std::vector<std::uint32_t> narrow(n);
  std::vector<std::uint64_t> wide(n);
  for (std::size_t i = 0; i < n; ++i) {
    narrow[i] = static_cast<std::uint32_t>((n - i) * 2654435761u);
    wide[i] = std::uint64_t(narrow[i]) * 0x9E3779B97F4A7C15ull;
  }
  std::vector<std::uint32_t> v1 = values;
  sort(narrow, v1, {32, 0});
  sort(wide, values, {64, 0});
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace raysort

// raysort sortbench: throughput of our radix sort (host/sort) against the host's std::stable_sort
// and std::sort, a plain LSD radix sort on the host's threads (host/sort/host_lsd_sort.h, the
// anchor a user could write in 60 lines), Boost.Compute's sort_by_key on the same device (when its
// headers are installed), and the device's copy-bandwidth bound. Device times come from profiling events, medians over
// --reps after a warm-up; program builds and first launches are reported apart.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/options.h"
#include "runtime/runtime.h"
#include "sort/host_lsd_sort.h"
#include "sort/radix_sort.h"
#include "util/parallel.h"

#if __has_include(<boost/compute/algorithm/sort_by_key.hpp>)
#include <boost/compute/algorithm/sort_by_key.hpp>
#include <boost/compute/command_queue.hpp>
#include <boost/compute/context.hpp>
#include <boost/compute/iterator/buffer_iterator.hpp>
#define RAYSORT_HAVE_BOOST_COMPUTE 1
#else
#define RAYSORT_HAVE_BOOST_COMPUTE 0
#endif

namespace raysort {

namespace {

struct Options {
  std::string device;
  int reps = 10;
  int ref_reps = 3;
  bool large = true;
  std::vector<unsigned> bits = {32, 64};
  bool gpu_shape = false;  // the GPU shape on any device (local-memory tiles; both kinds of passes)
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

template <class F>
double wall_ms(F&& f) {
  auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Device copy bandwidth (bytes read + written per second) from clEnqueueCopyBuffer, median of 5.
double copy_bandwidth(Runtime& rt) {
  const std::size_t bytes = std::min<std::size_t>(256u << 20, rt.info().max_alloc_bytes / 2);
  cl::Buffer a = rt.buffer("copy-bandwidth source", bytes), b = rt.buffer("copy-bandwidth target", bytes);
  std::vector<double> ms;
  for (int i = 0; i < 6; ++i) {
    cl::Event e;
    rt.queue().enqueueFillBuffer(a, cl_uint(i), 0, bytes);
    rt.queue().enqueueCopyBuffer(a, b, 0, 0, bytes, nullptr, &e);
    e.wait();
    if (i > 0) ms.push_back(event_ms(e));  // the first copy touches fresh pages
  }
  return 2.0 * static_cast<double>(bytes) / (median(ms) * 1e-3);
}

template <class Key>
struct Pair {
  Key key;
  std::uint32_t value;
};

struct Row {
  std::size_t n = 0;
  unsigned bits = 0;
  std::string keys;
  SortStats stats;
  double ours = 0, ours_ms = 0, bound = 0, stable = 0, unstable = 0, host_lsd = 0, boost = -1, boost_first_ms = 0;
  double warp = -1;          // the warp-granular sort (group 32), Mkeys/s; -1: this shape has none
  double warp_saving = 0;    // median over reps of full ms / warp ms, the two sorted back to back
  bool ok = false;           // ours equals std::stable_sort
  bool lsd_ok = false;       // the host LSD anchor equals std::stable_sort
  bool warp_ok = true;       // the warp-granular sort equals its host twin
  // The GPU shape's other kind of passes (Onesweep when ours runs reduce-then-scan, and the other
  // way round), sorted back to back with ours: Mkeys/s (-1: not run) and the median of ours ms /
  // its ms over the reps.
  double other = -1, other_saving = 0;
  bool other_ok = true;
  std::vector<SortStats> full_reps;  // the full sort's stats of every timed rep (where the time goes)
};

// The keys of a case; few-distinct: only the 16 highest key bits are random (at most 65536 keys).
template <class Key>
std::vector<Key> case_keys(std::size_t n, unsigned bits, bool few) {
  std::mt19937_64 rng(n * 131 + bits * 7 + few);
  std::vector<Key> keys(n);
  for (auto& k : keys) k = few ? static_cast<Key>((rng() & 0xFFFF) << (bits - 16)) : static_cast<Key>(rng());
  return keys;
}

// std::stable_sort and std::sort on (key, value) pairs; returns stable_sort's result, the reference.
template <class Key>
std::vector<Pair<Key>> host_sorts(const std::vector<Key>& keys, const std::vector<std::uint32_t>& values,
                                  const Options& opt, Row& row) {
  const std::size_t n = keys.size();
  std::vector<Pair<Key>> pairs(n), expected;
  for (std::size_t i = 0; i < n; ++i) pairs[i] = {keys[i], values[i]};
  auto by_key = [](const Pair<Key>& a, const Pair<Key>& b) { return a.key < b.key; };
  std::vector<double> stable_ms, unstable_ms, lsd_ms;
  for (int r = 0; r < opt.ref_reps; ++r) {
    auto p = pairs;
    stable_ms.push_back(wall_ms([&] { std::stable_sort(p.begin(), p.end(), by_key); }));
    if (r == 0) expected = p;
    p = pairs;
    unstable_ms.push_back(wall_ms([&] { std::sort(p.begin(), p.end(), by_key); }));
  }
  // The host LSD anchor on the same keys: separate key and value arrays, as ours sorts them.
  HostLsdScratch<Key> scratch;
  for (int r = -1; r < opt.ref_reps; ++r) {  // rep -1: touches the scratch pages, not timed
    std::vector<Key> k = keys;
    std::vector<std::uint32_t> v = values;
    const double ms = wall_ms([&] { host_lsd_sort(k, v, row.bits, scratch); });
    if (r >= 0) lsd_ms.push_back(ms);
    if (r == -1) {
      row.lsd_ok = true;
      for (std::size_t i = 0; i < n && row.lsd_ok; ++i) row.lsd_ok = k[i] == expected[i].key && v[i] == expected[i].value;
    }
  }
  const double nk = static_cast<double>(n) * 1e-3;  // keys per ms -> Mkeys/s
  row.stable = nk / median(stable_ms);
  row.unstable = nk / median(unstable_ms);
  row.host_lsd = nk / median(lsd_ms);
  return expected;
}

// The input kept pristine on the device, copied into the buffers a sort works in before each rep.
template <class Key>
struct DeviceInput {
  Runtime& rt;
  std::size_t n;
  cl::Buffer src_keys, src_values, work_keys, work_values;
  DeviceInput(Runtime& r, const std::vector<Key>& keys, const std::vector<std::uint32_t>& values)
      : rt(r), n(keys.size()), src_keys(r.upload("bench keys", keys)), src_values(r.upload("bench values", values)),
        work_keys(r.buffer("bench work keys", n * sizeof(Key))), work_values(r.buffer("bench work values", n * 4)) {}
  void restore() {
    rt.queue().enqueueCopyBuffer(src_keys, work_keys, 0, 0, n * sizeof(Key));
    rt.queue().enqueueCopyBuffer(src_values, work_values, 0, 0, n * 4);
    rt.queue().finish();
  }
  // Whether the work buffers hold exactly these pairs.
  bool holds(const std::vector<Key>& keys, const std::vector<std::uint32_t>& values) {
    std::vector<Key> got_keys;
    std::vector<std::uint32_t> got_values;
    rt.download("sorted keys", work_keys, got_keys, n);
    rt.download("sorted values", work_values, got_values, n);
    return got_keys == keys && got_values == values;
  }
};

// Ours, the full sort, with (on the CPU shape) the warp-granular one and (on the GPU shape, when
// given) the other kind of passes, back to back in every rep, in an order that rotates every rep;
// rep -1 is the untimed warm-up whose results are checked.
template <class Key>
void time_ours(RadixSort& sorter, RadixSort* other, DeviceInput<Key>& in, const std::vector<Pair<Key>>& expected,
               const std::vector<Key>& keys, const std::vector<std::uint32_t>& values, const Options& opt, Row& row) {
  RadixSortConfig full{row.bits, 0}, warp{row.bits, 0};
  warp.warp_group = 32;
  enum Arm { Full, Warp, Other };
  std::vector<Arm> arms = {Full};
  if (sorter.warp_sort_shape()) arms.push_back(Warp);
  if (other) arms.push_back(Other);
  std::vector<double> full_ms, warp_ms, warp_saving, other_ms, other_saving;
  std::vector<Key> want_keys(expected.size());
  std::vector<std::uint32_t> want_values(expected.size());
  for (std::size_t j = 0; j < expected.size(); ++j) want_keys[j] = expected[j].key, want_values[j] = expected[j].value;
  for (int r = -1; r < opt.reps; ++r) {
    double ms[3] = {0, 0, 0};
    for (std::size_t i = 0; i < arms.size(); ++i) {
      const Arm arm = arms[(i + static_cast<std::size_t>(r + 1)) % arms.size()];
      in.restore();
      const SortStats s = (arm == Other ? *other : sorter).sort(in.work_keys, in.work_values, in.n,
                                                                arm == Warp ? warp : full);
      ms[arm] = s.ms;
      if (arm == Full) row.stats = s;
      if (r != -1) continue;
      if (arm == Full) row.ok = in.holds(want_keys, want_values);
      if (arm == Other) row.other_ok = in.holds(want_keys, want_values);
      if (arm == Warp) {
        std::vector<Key> k = keys;
        std::vector<std::uint32_t> v = values;
        reference_warp_sort(k, v, warp);
        row.warp_ok = in.holds(k, v);
      }
    }
    if (r < 0) continue;
    row.full_reps.push_back(row.stats);
    full_ms.push_back(ms[Full]);
    if (sorter.warp_sort_shape()) warp_ms.push_back(ms[Warp]), warp_saving.push_back(ms[Full] / ms[Warp]);
    if (other) other_ms.push_back(ms[Other]), other_saving.push_back(ms[Full] / ms[Other]);
  }
  const double nk = static_cast<double>(in.n) * 1e-3;
  row.ours_ms = median(full_ms);
  row.ours = nk / row.ours_ms;
  if (!warp_ms.empty()) row.warp = nk / median(warp_ms), row.warp_saving = median(warp_saving);
  if (!other_ms.empty()) row.other = nk / median(other_ms), row.other_saving = median(other_saving);
}

// Where the time of a case's full sort goes: per command (kernel, read-back, copy) its launches
// and the median over the reps of its summed device time, then the gaps between commands (the sort's
// span less its commands: launch latency and the host's waits for a read-back).
void print_time_by_command(const Row& r) {
  if (r.full_reps.empty()) return;
  fmt::print("\nwhere the time goes, {} {} {}-bit keys (median of {} reps, profiling events):\n\n", r.n, r.keys,
             r.bits, r.full_reps.size());
  fmt::print("| command | launches | ms | % of the sort |\n|---|---:|---:|---:|\n");
  std::vector<double> spans, gaps;
  for (const SortStats& s : r.full_reps) spans.push_back(s.ms), gaps.push_back(s.ms - s.kernel_ms);
  const double total = median(spans);
  for (const SortCommandTime& c : r.full_reps.front().commands) {
    std::vector<double> ms;
    for (const SortStats& s : r.full_reps)
      for (const SortCommandTime& d : s.commands)
        if (d.name == c.name) ms.push_back(d.ms);
    fmt::print("| {} | {} | {:.3f} | {:.0f}% |\n", c.name, c.launches, median(ms), 100.0 * median(ms) / total);
  }
  fmt::print("| gaps between commands | | {:.3f} | {:.0f}% |\n", median(gaps), 100.0 * median(gaps) / total);
  fmt::print("| the sort (first command's start to last's end) | | {:.3f} | 100% |\n", total);
}

template <class Key>
void time_boost_compute([[maybe_unused]] Runtime& rt, [[maybe_unused]] DeviceInput<Key>& in,
                        [[maybe_unused]] const Options& opt, [[maybe_unused]] Row& row) {
#if RAYSORT_HAVE_BOOST_COMPUTE
  namespace bc = boost::compute;
  bc::context context(rt.context()(), true);
  bc::command_queue queue(rt.queue()(), true);
  bc::buffer bk(in.work_keys(), true), bv(in.work_values(), true);
  auto boost_sort = [&] {
    bc::sort_by_key(bc::make_buffer_iterator<Key>(bk, 0), bc::make_buffer_iterator<Key>(bk, in.n),
                    bc::make_buffer_iterator<std::uint32_t>(bv, 0), queue);
    queue.finish();
  };
  in.restore();
  row.boost_first_ms = wall_ms(boost_sort);  // builds Boost.Compute's programs: reported apart
  std::vector<double> boost_ms;
  for (int r = 0; r < opt.ref_reps; ++r) {
    in.restore();
    boost_ms.push_back(wall_ms(boost_sort));
  }
  row.boost = static_cast<double>(in.n) * 1e-3 / median(boost_ms);
#endif
}

template <class Key>
Row bench_case(Runtime& rt, RadixSort& sorter, RadixSort* other, double bandwidth, std::size_t n, unsigned bits,
               bool few, const Options& opt) {
  Row row;
  row.n = n;
  row.bits = bits;
  row.keys = few ? "few-distinct" : "random";
  const std::vector<Key> keys = case_keys<Key>(n, bits, few);
  std::vector<std::uint32_t> values(n);
  std::iota(values.begin(), values.end(), 0u);
  const std::vector<Pair<Key>> expected = host_sorts(keys, values, opt, row);
  DeviceInput<Key> in(rt, keys, values);
  time_ours(sorter, other, in, expected, keys, values, opt, row);
  // The copy-bandwidth bound: every pass that runs reads and writes all keys and values once,
  // and the upfront histogram reads the keys once.
  const double bytes = static_cast<double>(n) * (row.stats.passes_run * 2.0 * (sizeof(Key) + 4) + sizeof(Key));
  row.bound = static_cast<double>(n) * 1e-3 / (bytes / bandwidth * 1e3);
  time_boost_compute(rt, in, opt, row);
  return row;
}

void run_sortbench(const Options& opt) {
  Runtime rt(select_device(opt.device));
  fmt::print("device: {} ({}, {} compute units)\n", rt.info().name, rt.info().platform_name, rt.info().compute_units);
  if (std::ifstream load("/proc/loadavg"); load) {  // other work on the machine skews every column
    std::string one, five;
    load >> one >> five;
    fmt::print("host load average (1, 5 min): {} {}\n", one, five);
  }
  // --gpu-shape on a CPU: the shape for_device gives a GPU with this device's work-group limit and
  // at most 48 KiB of local memory (NVIDIA's OpenCL limit), fitted to what the kernels take here.
  DeviceInfo shape_of = rt.info();
  if (opt.gpu_shape && shape_of.type != "GPU")
    shape_of.type = "GPU", shape_of.local_mem_bytes = std::min<std::uint64_t>(shape_of.local_mem_bytes, 48 * 1024);
  RadixSort sorter(rt, RadixSortTuning::for_device(shape_of), RadixSortFit::ShrinkToKernels);
  const auto& t = sorter.tuning();
  fmt::print("radix sort: {}-bit digits, work-group {}, {}; programs built in {:.0f} ms\n", t.radix_bits,
             t.work_group,
             t.work_group == 1 ? fmt::format("tiles of >= {} keys, {} per compute unit{}", t.min_tile, t.tiles_per_unit,
                                             t.hybrid() ? fmt::format(", MSD-first hybrid from {} pairs", t.hybrid_min)
                                                        : std::string())
                               : fmt::format("{} keys per work-item", t.items),
             rt.build_ms());
  fmt::print("first launches (warm-up, both key widths): {:.0f} ms\n", sorter.warm_up());
  // The GPU shape's passes: reduce-then-scan (count, scan, scatter) or Onesweep (one kernel per
  // pass, decoupled look-back; for_device picks it on NVIDIA). The other kind runs beside ours.
  std::unique_ptr<RadixSort> other;
  if (t.work_group > 1) {
    RadixSortTuning ot = t;
    ot.onesweep = !t.onesweep;
    try {
      other = std::make_unique<RadixSort>(rt, ot, RadixSortFit::ShrinkToKernels);
      other->warm_up();
    } catch (const Error& e) {
      fmt::print("{} passes: not run beside ours ({})\n", ot.gpu_passes(), e.what());
    }
  }
  fmt::print("passes: ours {}{}\n", t.work_group == 1 ? "CPU shape" : t.gpu_passes(),
             other ? fmt::format("; other passes: {}, sorted back to back with ours in every rep, ours/other time the "
                                 "median of the reps' ratios", other->tuning().gpu_passes())
                   : std::string());
  const double bandwidth = copy_bandwidth(rt);
  fmt::print("copy bandwidth (clEnqueueCopyBuffer, read + write): {:.1f} GB/s\n", bandwidth * 1e-9);
  fmt::print("ours: median of {} reps, profiling events; host sorts and Boost.Compute: median of {} reps, wall clock\n",
             opt.reps, opt.ref_reps);
  fmt::print("host LSD: 8-bit digits, stable, {} threads (host/sort/host_lsd_sort.h)\n", host_threads());
  fmt::print("warp 32: ours stopping at groups of 32 pairs (run --warp-sort, docs/sort.md), sorted back to back with "
             "the full sort in every rep; full/warp time: the median of the reps' ratios\n");
#if !RAYSORT_HAVE_BOOST_COMPUTE
  fmt::print("Boost.Compute: headers not installed (libboost-dev), column left empty\n");
#endif
  fmt::print("\n| pairs | key bits | keys | passes run/skipped | ours Mkeys/s | ours ms | copy bound Mkeys/s | "
             "% of bound | std::stable_sort | std::sort | host LSD | Boost.Compute | x stable_sort | x host LSD | x Boost | "
             "warp 32 Mkeys/s | full/warp time | other passes Mkeys/s | ours/other time | ok |\n");
  fmt::print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  std::vector<std::size_t> sizes = {2073600};
  if (opt.large) sizes.push_back(16u << 20);
  std::vector<Row> rows;
  bool all_ok = true;
  for (std::size_t n : sizes)
    for (unsigned bits : opt.bits)
      for (bool few : {false, true}) {
        Row r = bits == 64 ? bench_case<std::uint64_t>(rt, sorter, other.get(), bandwidth, n, bits, few, opt)
                           : bench_case<std::uint32_t>(rt, sorter, other.get(), bandwidth, n, bits, few, opt);
        all_ok = all_ok && r.ok && r.lsd_ok && r.warp_ok && r.other_ok;
        auto boost = [&](double v) { return r.boost < 0 ? std::string("-") : fmt::format("{:.1f}", v); };
        fmt::print(
            "| {} | {} | {} | {}/{} | {:.1f} | {:.2f} | {:.1f} | {:.0f}% | {:.1f} | {:.1f} | {:.1f} | {} | {:.1f} | {:.2f} | {} "
            "| {} | {} | {} | {} | {} |\n",
            r.n, r.bits, r.keys, r.stats.passes_run, r.stats.passes_skipped, r.ours, r.ours_ms, r.bound,
            100.0 * r.ours / r.bound, r.stable, r.unstable, r.host_lsd, boost(r.boost), r.ours / r.stable,
            r.ours / r.host_lsd, boost(r.ours / r.boost), r.warp < 0 ? "-" : fmt::format("{:.1f}", r.warp),
            r.warp < 0 ? "-" : fmt::format("{:.2f}", r.warp_saving),
            r.other < 0 ? "-" : fmt::format("{:.1f}", r.other), r.other < 0 ? "-" : fmt::format("{:.2f}", r.other_saving),
            !r.ok         ? "NO"
            : !r.lsd_ok   ? "NO (host LSD)"
            : !r.warp_ok  ? "NO (warp sort)"
            : !r.other_ok ? "NO (other passes)"
                          : "yes");
        std::fflush(stdout);
        rows.push_back(r);
      }
  // The first case (2 M random keys of the first width): the batch size the matrix sorts.
  if (!rows.empty()) print_time_by_command(rows.front());
#if RAYSORT_HAVE_BOOST_COMPUTE
  fmt::print("\nBoost.Compute first call (program builds) per case, ms:");
  for (auto& r : rows) fmt::print(" {:.0f}", r.boost_first_ms);
  fmt::print("\n");
#endif
  if (!all_ok) {
    fmt::print("FAILED: a sorted result (ours, the host LSD anchor, the warp sort against its twin, or the other "
               "passes) differs\n");
    set_command_exit_code(1);
  }
}

}  // namespace

void register_sortbench_command(CLI::App& app) {
  static Options opt;
  auto* cmd = app.add_subcommand("sortbench", "benchmark the radix sort against host sorts and Boost.Compute");
  cmd->add_option("--device", opt.device, "OpenCL device: index, cpu, gpu or a name substring (default: first GPU)");
  whole_number(cmd->add_option("--reps", opt.reps, "timed repetitions of our sort per case (median)"), 1, 1000);
  whole_number(cmd->add_option("--ref-reps", opt.ref_reps, "repetitions of the host sorts and Boost.Compute per case"), 1,
               100);
  cmd->add_flag("!--no-large", opt.large, "skip the 16 M pair cases");
  cmd->add_option("--bits", opt.bits, "key widths to run, comma-separated: 32, 64 or both (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({32u, 64u}));
  cmd->add_flag("--gpu-shape", opt.gpu_shape,
                "sort in the GPU shape (local-memory tiles, reduce-then-scan beside Onesweep) on any device");
  cmd->callback([] { run_sortbench(opt); });
}

}  // namespace raysort

// The OpenCL radix sort (host/sort, cl/radix_sort.cl) against its host twin, std::stable_sort:
// keys and values must match bit for bit (values are the input positions, so any instability
// shows), for every input shape, size and key width, in full and top-k mode, and on both kernel
// paths (the CPU shape picked for this device and a GPU shape forced onto it).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sort/host_lsd_sort.h"
#include "sort/permute.h"
#include "sort/radix_sort.h"
#include "test_util.h"

namespace raysort {
namespace {

enum class Shape { Uniform, Sorted, Reversed, AllEqual, AllOnes, FewDistinct, HighBits16, LowBits };
const Shape kShapes[] = {Shape::Uniform,  Shape::Sorted,      Shape::Reversed,   Shape::AllEqual,
                         Shape::AllOnes, Shape::FewDistinct, Shape::HighBits16, Shape::LowBits};

const char* name(Shape s) {
  switch (s) {
    case Shape::Uniform: return "uniform";
    case Shape::Sorted: return "sorted";
    case Shape::Reversed: return "reversed";
    case Shape::AllEqual: return "all-equal";
    case Shape::AllOnes: return "all-ones";
    case Shape::FewDistinct: return "few-distinct";
    case Shape::HighBits16: return "high-16-bits";
    case Shape::LowBits: return "low-8-bits";
  }
  return "?";
}

std::uint64_t mask_of(unsigned bits) { return bits >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << bits) - 1; }

// Keys of `bits` bits (fixed seed per case, so a failure reproduces).
std::vector<std::uint64_t> make_keys(Shape shape, std::size_t n, unsigned bits, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const std::uint64_t mask = mask_of(bits);
  std::vector<std::uint64_t> k(n);
  std::vector<std::uint64_t> pool(16);
  for (auto& p : pool) p = rng() & mask;
  const std::uint64_t constant = rng() & mask;
  for (std::size_t i = 0; i < n; ++i) {
    switch (shape) {
      case Shape::Uniform:
      case Shape::Sorted:
      case Shape::Reversed: k[i] = rng() & mask; break;
      case Shape::AllEqual: k[i] = constant; break;
      case Shape::AllOnes: k[i] = mask; break;
      case Shape::FewDistinct: k[i] = pool[rng() % pool.size()]; break;
      case Shape::HighBits16: k[i] = bits <= 16 ? rng() & mask : (rng() & 0xFFFF) << (bits - 16); break;
      case Shape::LowBits: k[i] = rng() & 0xFF & mask; break;
    }
  }
  if (shape == Shape::Sorted) std::sort(k.begin(), k.end());
  if (shape == Shape::Reversed) std::sort(k.begin(), k.end(), std::greater<>());
  return k;
}

struct Device {
  std::unique_ptr<Runtime> rt;
  std::unique_ptr<RadixSort> cpu_shape;  // RadixSortTuning::for_device (this device: a CPU)
  std::unique_ptr<RadixSort> gpu_shape;  // the work-group ranking path, forced onto this device
  std::unique_ptr<RadixSort> hybrid;     // the CPU shape with the MSD-first hybrid at every size
  std::unique_ptr<RadixSort> hybrid_any_skew;  // ... that never falls back to the LSD passes
  std::unique_ptr<RadixSort> onesweep;         // the GPU shape with the Onesweep passes, forced
  std::unique_ptr<RadixSort> onesweep_small;   // ... with 32-key tiles and 4-bit digits: many tiles
};

Device& device() {
  static Device d = [] {
    Device d;
    d.rt = std::make_unique<Runtime>(select_device(""));
    d.cpu_shape = std::make_unique<RadixSort>(*d.rt);
    // The shape for_device picks for a GPU with 48 KiB of local memory (NVIDIA's OpenCL limit).
    DeviceInfo gpu = d.rt->info();
    gpu.type = "GPU";
    gpu.local_mem_bytes = 48 * 1024;
    gpu.max_work_group_size = 1024;
    RadixSortTuning tuning = RadixSortTuning::for_device(gpu);
    EXPECT_GT(tuning.work_group, 1u);
    EXPECT_LE(tuning.local_bytes(8), gpu.local_mem_bytes);
    d.gpu_shape = std::make_unique<RadixSort>(*d.rt, tuning);
    EXPECT_FALSE(tuning.onesweep) << "Onesweep chosen for a device that is not NVIDIA's";
    tuning.onesweep = true;
    d.onesweep = std::make_unique<RadixSort>(*d.rt, tuning);
    tuning.work_group = 32;
    tuning.items = 1;
    tuning.radix_bits = 4;
    tuning.scan_work_group = 32;
    d.onesweep_small = std::make_unique<RadixSort>(*d.rt, tuning);
    RadixSortTuning hybrid = RadixSortTuning::for_device(d.rt->info());
    if (hybrid.work_group == 1) {
      hybrid.hybrid_min = 2;
      d.hybrid = std::make_unique<RadixSort>(*d.rt, hybrid);
      hybrid.hybrid_skew = 1;
      d.hybrid_any_skew = std::make_unique<RadixSort>(*d.rt, hybrid);
    }
    return d;
  }();
  return d;
}

// Sorts with `sorter` and with std::stable_sort; returns the device's stats.
SortStats check(RadixSort& sorter, const std::vector<std::uint64_t>& keys64, RadixSortConfig cfg,
                const std::string& what) {
  std::vector<std::uint32_t> values(keys64.size());
  std::iota(values.begin(), values.end(), 0u);
  std::vector<std::uint32_t> expected_values = values;
  SortStats stats;
  auto twin = [&cfg](auto& k, auto& v) { cfg.warp_group > 0 ? reference_warp_sort(k, v, cfg) : reference_sort(k, v, cfg); };
  if (cfg.wide_keys()) {
    std::vector<std::uint64_t> keys = keys64, expected = keys64;
    twin(expected, expected_values);
    stats = sorter.sort(keys, values, cfg);
    EXPECT_TRUE(keys == expected) << what << ": keys differ from std::stable_sort";
  } else {
    std::vector<std::uint32_t> keys(keys64.begin(), keys64.end());
    std::vector<std::uint32_t> expected = keys;
    twin(expected, expected_values);
    stats = sorter.sort(keys, values, cfg);
    EXPECT_TRUE(keys == expected) << what << ": keys differ from std::stable_sort";
  }
  EXPECT_TRUE(values == expected_values) << what << ": values differ from std::stable_sort (order not stable?)";
  // The warp-granular sort runs one global pass and one walk of the buckets.
  if (cfg.warp_group > 0)
    EXPECT_LE(stats.passes_run, 2u) << what;
  else
    EXPECT_EQ(stats.passes_run + stats.passes_skipped, sorter.passes(cfg)) << what;
  return stats;
}

const std::size_t kSizes[] = {0, 1, 2, 31, 32, 33, 1000, 65537, (1u << 20) + 3};
const unsigned kKeyBits[] = {16, 32, 64};

TEST(Sort, MatchesStableSortEveryShapeSizeAndWidth) {
  auto& sorter = *device().cpu_shape;
  for (unsigned bits : kKeyBits)
    for (Shape shape : kShapes)
      for (std::size_t n : kSizes) {
        auto keys = make_keys(shape, n, bits, 1000 * bits + n + static_cast<int>(shape));
        check(sorter, keys, {bits, 0}, fmt::format("{} keys of {} bits, n = {}", name(shape), bits, n));
      }
}

TEST(Sort, GpuShapeMatchesStableSort) {
  // The local-memory ranking path (RS_WG > 1) run on this device; fewer sizes, it is slow on a CPU.
  auto& sorter = *device().gpu_shape;
  for (unsigned bits : kKeyBits)
    for (Shape shape : kShapes)
      for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(33), std::size_t(1000), std::size_t(65537)}) {
        auto keys = make_keys(shape, n, bits, 7000 * bits + n + static_cast<int>(shape));
        check(sorter, keys, {bits, 0}, fmt::format("gpu shape: {} keys of {} bits, n = {}", name(shape), bits, n));
      }
  auto keys = make_keys(Shape::Uniform, (1u << 20) + 3, 64, 99);
  check(sorter, keys, {64, 0}, "gpu shape: 1M+3 uniform 64-bit keys");
}

TEST(Sort, OnesweepMatchesStableSort) {
  // The Onesweep passes (one histogram read, then per pass one kernel with a decoupled look-back)
  // forced onto this device, whose work-groups run on several threads at once: tiles of 2048 keys
  // (0, 1, 2048, 2049 sit on tile boundaries) and of 32 keys (65537 keys: 2049 tiles looking back).
  for (RadixSort* sorter : {device().onesweep.get(), device().onesweep_small.get()}) {
    const std::string shape = sorter == device().onesweep.get() ? "onesweep" : "onesweep, 32-key tiles";
    for (unsigned bits : kKeyBits)
      for (Shape s : kShapes)
        for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(2048), std::size_t(2049),
                              std::size_t(65537)}) {
          auto keys = make_keys(s, n, bits, 9000 * bits + n + static_cast<int>(s));
          check(*sorter, keys, {bits, 0}, fmt::format("{}: {} keys of {} bits, n = {}", shape, name(s), bits, n));
          check(*sorter, keys, {bits, bits / 2}, fmt::format("{}: {} keys of {} bits, top {}, n = {}", shape, name(s),
                                                             bits, bits / 2, n));
        }
  }
  auto keys = make_keys(Shape::Uniform, (1u << 20) + 3, 64, 98);
  const SortStats st = check(*device().onesweep, keys, {64, 0}, "onesweep: 1M+3 uniform 64-bit keys");
  // One kernel per pass: no count, scan or scatter launches.
  for (const SortCommandTime& c : st.commands) {
    EXPECT_TRUE(c.name != "rs_count" && c.name != "rs_scan" && c.name != "rs_scatter") << c.name;
    if (c.name == "rs_onesweep" || c.name == "rs_sweep_clear") {  // a pass's status table zeroed before it
      EXPECT_EQ(c.launches, st.passes_run) << c.name;
    }
    if (c.name == "rs_hist_all") {
      EXPECT_EQ(c.launches, 1u);
    }
  }
}

TEST(Sort, OnesweepIsChosenForNvidiaAndNeedsTheGpuShape) {
  DeviceInfo gpu = device().rt->info();
  gpu.type = "GPU";
  gpu.local_mem_bytes = 48 * 1024;
  gpu.max_work_group_size = 1024;
  gpu.platform_name = "NVIDIA CUDA";
  EXPECT_TRUE(RadixSortTuning::for_device(gpu).onesweep);
  gpu.platform_name = "Oclgrind";
  EXPECT_FALSE(RadixSortTuning::for_device(gpu).onesweep);
  RadixSortTuning cpu = RadixSortTuning::for_device(device().rt->info());
  EXPECT_FALSE(cpu.onesweep);
  cpu.work_group = 1;
  cpu.onesweep = true;
  try {
    RadixSort refused(*device().rt, cpu);
    ADD_FAILURE() << "Onesweep with one work-item per tile was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("GPU shape"), std::string::npos) << e.what();
  }
}

TEST(Sort, ShrinksALaunchToWhatItsKernelTakes) {
  // NVIDIA's H200 takes 1024 work-items per group but its rs_scan only 256: the device's own shape
  // must fit itself to each kernel (it once refused to sort there), and a forced shape is refused.
  // Here a scan of 8192 work-items, more than PoCL's kernels take, stands for that.
  DeviceInfo gpu = device().rt->info();
  gpu.type = "GPU";
  gpu.local_mem_bytes = 48 * 1024;
  gpu.max_work_group_size = 1024;
  RadixSortTuning tuning = RadixSortTuning::for_device(gpu);
  tuning.scan_work_group = 8192;
  try {
    RadixSort exact(*device().rt, tuning);
    ADD_FAILURE() << "a forced scan of 8192 work-items was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("force"), std::string::npos) << e.what();
  }
  RadixSort fitted(*device().rt, tuning, RadixSortFit::ShrinkToKernels);
  const unsigned scan = fitted.tuning().scan_work_group;
  EXPECT_LT(scan, 8192u);
  EXPECT_EQ(scan & (scan - 1), 0u) << scan << " is not a power of two";
  EXPECT_EQ(fitted.tuning().work_group, tuning.work_group);
  for (unsigned bits : {32u, 64u})
    for (std::size_t n : {std::size_t(1), std::size_t(1000), std::size_t(65537)})
      check(fitted, make_keys(Shape::Uniform, n, bits, 31 * bits + n), {bits, 0},
            fmt::format("scan shrunk to {}: {} keys of {} bits", scan, n, bits));
}

TEST(Sort, StatsSayWhereTheTimeGoesByCommand) {
  // sortbench's "where the time goes" table (issue 42: on an H200 the sort cost more than the trace):
  // every profiled command is counted once under its name, and the commands add up to kernel_ms.
  for (RadixSort* sorter : {device().cpu_shape.get(), device().gpu_shape.get()}) {
    const bool gpu = sorter == device().gpu_shape.get();
    auto keys = make_keys(Shape::Uniform, 65537, 32, 5);
    const SortStats st = check(*sorter, keys, {32, 0}, gpu ? "gpu shape, by command" : "cpu shape, by command");
    ASSERT_FALSE(st.commands.empty());
    double sum = 0.0;
    unsigned launches = 0, scatters = 0;
    for (const SortCommandTime& c : st.commands) {
      EXPECT_FALSE(c.name.empty());
      EXPECT_EQ(c.name.find('\0'), std::string::npos) << "a NUL in the command name " << c.name;
      EXPECT_GE(c.launches, 1u) << c.name;
      sum += c.ms, launches += c.launches;
      if (c.name == "rs_scatter") scatters = c.launches;
    }
    EXPECT_NEAR(sum, st.kernel_ms, 1e-9 * std::max(1.0, st.kernel_ms));
    EXPECT_GE(launches, 3u);  // the first read's kernels and its read-back at least
    if (gpu) {
      EXPECT_EQ(scatters, st.passes_run) << "one rs_scatter per pass that moved keys";
    }
  }
}

TEST(Sort, HybridMatchesStableSort) {
  // The MSD-first hybrid (large N on the CPU shape), forced at every size.
  if (!device().hybrid) GTEST_SKIP() << "this device's shape has no hybrid path";
  for (RadixSort* sorter : {device().hybrid.get(), device().hybrid_any_skew.get()})
    for (unsigned bits : kKeyBits)
      for (Shape shape : kShapes)
        for (std::size_t n : {std::size_t(2), std::size_t(33), std::size_t(1000), std::size_t(65537),
                              std::size_t(1u << 20) + 3}) {
          auto keys = make_keys(shape, n, bits, 5000 * bits + n + static_cast<int>(shape));
          check(*sorter, keys, {bits, 0},
                fmt::format("hybrid (skew {}): {} keys of {} bits, n = {}", sorter->tuning().hybrid_skew, name(shape),
                            bits, n));
        }
  // Skewed: most keys share the top digit (the fallback to LSD passes, or one huge bucket).
  for (unsigned bits : {32u, 64u}) {
    auto keys = make_keys(Shape::Uniform, 300007, bits, 77 + bits);
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (i % 10 != 0) keys[i] &= mask_of(bits - 8);
    for (RadixSort* sorter : {device().hybrid.get(), device().hybrid_any_skew.get()}) {
      auto stats = check(*sorter, keys, {bits, 0}, fmt::format("hybrid, skewed {}-bit keys", bits));
      EXPECT_EQ(stats.passes_run, sorter->passes({bits, 0}));
    }
  }
  for (auto [bits, top] : {std::pair{16u, 9u}, {32u, 5u}, {32u, 13u}, {32u, 24u}, {64u, 21u}, {64u, 33u}, {64u, 64u}})
    for (std::size_t n : {std::size_t(1000), std::size_t(300007)}) {
      auto keys = make_keys(Shape::Uniform, n, bits, bits * 17 + top + n);
      check(*device().hybrid, keys, {bits, top}, fmt::format("hybrid: top {} of {} bits, n = {}", top, bits, n));
    }
}

TEST(Sort, TopBitsOrderByTheHighBitsOnly) {
  struct Case {
    unsigned bits, top;
  };
  for (auto [bits, top] : {Case{16, 4}, Case{16, 9}, Case{32, 1}, Case{32, 5}, Case{32, 8}, Case{32, 10},
                           Case{32, 13}, Case{32, 24}, Case{64, 3}, Case{64, 21}, Case{64, 33}, Case{64, 64}}) {
    for (std::size_t n : {std::size_t(1000), std::size_t(65537), std::size_t(300007)}) {
      auto keys = make_keys(Shape::Uniform, n, bits, bits * 31 + top + n);
      check(*device().cpu_shape, keys, {bits, top}, fmt::format("top {} of {} bits, n = {}", top, bits, n));
      check(*device().gpu_shape, keys, {bits, top}, fmt::format("gpu shape: top {} of {} bits, n = {}", top, bits, n));
    }
  }
}

TEST(Sort, TopBitsReferenceIsCoarserThanFullSort) {
  // Guards the test itself: a top-k sort of random keys must not be a full sort, or the top-k
  // tests above could pass with a sorter that ignores top_bits.
  auto keys64 = make_keys(Shape::Uniform, 10000, 32, 5);
  std::vector<std::uint32_t> a(keys64.begin(), keys64.end()), b = a, va(a.size()), vb(a.size());
  reference_sort(a, va, {32, 8});
  reference_sort(b, vb, {32, 0});
  EXPECT_FALSE(a == b);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end(), [](auto x, auto y) { return (x >> 24) < (y >> 24); }));
}

// The sort that stops at warp granularity (RadixSortConfig::warp_group) equals its host twin for
// every shape, size and width, with top-k, on the CPU shape and the hybrid's tuning.
TEST(Sort, WarpGranularMatchesItsHostTwin) {
  std::vector<RadixSort*> sorters = {device().cpu_shape.get()};
  if (device().hybrid) sorters.push_back(device().hybrid.get());
  for (RadixSort* sorter : sorters)
    for (unsigned group : {32u, 1u, 7u})
      for (unsigned bits : kKeyBits)
        for (Shape shape : kShapes)
          for (std::size_t n : kSizes) {
            if (group != 32 && n > 70000) continue;
            auto keys = make_keys(shape, n, bits, 9000 * bits + n + static_cast<int>(shape) + group);
            RadixSortConfig cfg{bits, 0};
            cfg.warp_group = group;
            check(*sorter, keys, cfg, fmt::format("warp group {}: {} keys of {} bits, n = {}", group, name(shape), bits, n));
          }
  for (auto [bits, top] : {std::pair{32u, 13u}, {32u, 24u}, {64u, 21u}, {16u, 9u}}) {
    auto keys = make_keys(Shape::Uniform, 300007, bits, bits + top);
    RadixSortConfig cfg{bits, top};
    cfg.warp_group = 32;
    check(*device().cpu_shape, keys, cfg, fmt::format("warp group 32, top {} of {} bits", top, bits));
  }
  // Clustered keys, as ray keys are: many pairs share long prefixes, so ranges split deep.
  auto keys = make_keys(Shape::Uniform, 500000, 32, 4242);
  for (std::size_t i = 0; i < keys.size(); ++i) keys[i] = (keys[i] % 3000) * 0x10101u;
  RadixSortConfig cfg{32, 0};
  cfg.warp_group = 32;
  check(*device().cpu_shape, keys, cfg, "warp group 32, clustered keys");
  // The GPU shape has no walk: a clear refusal, not a full sort under the warp sort's name.
  std::vector<std::uint32_t> k(100), v(100);
  EXPECT_THROW(device().gpu_shape->sort(k, v, cfg), Error);
}

// Guards the twin itself: coarser than the full sort (else the test above could pass with a full
// sort), the full sort at group 1, and every pair fewer than `group` places from its full-sort place.
TEST(Sort, WarpGranularTwinStopsAtGroupsOnly) {
  // Uniform keys: a top-digit bucket holds ~780 pairs, the next digit splits it into ranges of ~3.
  auto keys64 = make_keys(Shape::Uniform, 200000, 32, 77);
  std::vector<std::uint32_t> full(keys64.begin(), keys64.end()), warp = full, one = full;
  std::vector<std::uint32_t> vfull(full.size()), vwarp(full.size()), vone(full.size());
  std::iota(vfull.begin(), vfull.end(), 0u);
  vwarp = vone = vfull;
  RadixSortConfig cfg{32, 0};
  reference_sort(full, vfull, cfg);
  cfg.warp_group = 1;
  reference_warp_sort(one, vone, cfg);
  EXPECT_TRUE(one == full && vone == vfull) << "group 1 must be the full sort";
  cfg.warp_group = 32;
  reference_warp_sort(warp, vwarp, cfg);
  EXPECT_FALSE(warp == full) << "group 32 must leave some groups unsorted";
  std::vector<std::size_t> place(full.size());
  for (std::size_t i = 0; i < full.size(); ++i) place[vfull[i]] = i;
  std::size_t farthest = 0;
  for (std::size_t i = 0; i < warp.size(); ++i)
    farthest = std::max(farthest, i > place[vwarp[i]] ? i - place[vwarp[i]] : place[vwarp[i]] - i);
  EXPECT_LT(farthest, 32u);
  EXPECT_GT(farthest, 0u);
}

// `run --warp-sort` sorts every cell with warp_group 32 (its cells still reproduce NoSort's hits)
// and records it in meta.json's matrix; without it the entry is absent (sets written before resume).
TEST(SortCli, RunWarpSortIsRecorded) {
  for (bool warp : {true, false}) {
    const std::string out = testing::temp_path(warp ? "warp_sort_set" : "full_sort_set");
    std::vector<std::string> args = {"run",        "--scenes", "cornell", "--batches", "bounce1", "--encoders",
                                     "hcc",        "--resolution", "64x36", "--reps", "3", "--max-time", "0.05",
                                     "--out",      out};
    if (warp) args.push_back("--warp-sort");
    const testing::CliResult r = testing::run_cli(args);
    ASSERT_EQ(r.code, 0) << r.err;
    std::ifstream meta(out + "/meta.json");
    const nlohmann::json m = nlohmann::json::parse(meta);
    if (warp)
      EXPECT_EQ(m.at("matrix").value("sort_warp_group", 0u), 32u);
    else
      EXPECT_FALSE(m.at("matrix").contains("sort_warp_group"));
  }
}

TEST(Sort, SkipsPassesWhoseDigitIsConstant) {
  auto& sorter = *device().cpu_shape;  // 8-bit digits
  ASSERT_EQ(sorter.tuning().radix_bits, 8u);
  const std::size_t n = 100003;
  struct Case {
    Shape shape;
    unsigned bits, run, skipped;
  };
  for (auto c : {Case{Shape::Uniform, 32, 4, 0}, Case{Shape::Uniform, 16, 2, 0}, Case{Shape::Uniform, 64, 8, 0},
                 Case{Shape::LowBits, 32, 1, 3}, Case{Shape::LowBits, 64, 1, 7}, Case{Shape::HighBits16, 32, 2, 2},
                 Case{Shape::HighBits16, 64, 2, 6}, Case{Shape::AllEqual, 32, 0, 4}, Case{Shape::AllOnes, 64, 0, 8}}) {
    auto keys = make_keys(c.shape, n, c.bits, 42);
    auto stats = check(sorter, keys, {c.bits, 0}, fmt::format("{} keys of {} bits", name(c.shape), c.bits));
    EXPECT_EQ(stats.passes_run, c.run) << name(c.shape) << " " << c.bits;
    EXPECT_EQ(stats.passes_skipped, c.skipped) << name(c.shape) << " " << c.bits;
  }
  // 16-bit keys sort 16 bits: two passes, not four.
  EXPECT_EQ(sorter.passes({16, 0}), 2u);
  EXPECT_EQ(sorter.passes({32, 10}), 2u);
  EXPECT_EQ(sorter.passes({64, 0}), 8u);
}

TEST(Sort, DeviceBuffersAreSortedInPlaceAndReused) {
  // Larger buffers than the count: only the first `count` pairs move; calls of changing size on
  // the same sorter (scratch grown, then reused) stay correct.
  auto& d = device();
  const std::size_t capacity = 200000;
  std::vector<std::uint32_t> sentinel(capacity, 0xDEADBEEFu);
  cl::Buffer keys = d.rt->upload("test keys", sentinel, CL_MEM_READ_WRITE);
  cl::Buffer values = d.rt->upload("test values", sentinel, CL_MEM_READ_WRITE);
  for (std::size_t n : {std::size_t(150001), std::size_t(77), std::size_t(199999), std::size_t(5000)}) {
    auto k64 = make_keys(Shape::Uniform, n, 32, n);
    std::vector<std::uint32_t> k(k64.begin(), k64.end()), v(n);
    std::iota(v.begin(), v.end(), 0u);
    d.rt->queue().enqueueWriteBuffer(keys, CL_TRUE, 0, n * 4, k.data());
    d.rt->queue().enqueueWriteBuffer(values, CL_TRUE, 0, n * 4, v.data());
    auto stats = d.cpu_shape->sort(keys, values, n, {32, 0});
    EXPECT_GT(stats.ms, 0.0);
    EXPECT_GE(stats.ms, 0.5 * stats.kernel_ms);
    reference_sort(k, v, {32, 0});
    std::vector<std::uint32_t> got_k, got_v;
    d.rt->download("keys", keys, got_k, capacity);
    d.rt->download("values", values, got_v, capacity);
    EXPECT_TRUE(std::equal(k.begin(), k.end(), got_k.begin())) << n;
    EXPECT_TRUE(std::equal(v.begin(), v.end(), got_v.begin())) << n;
    EXPECT_EQ(got_k[capacity - 1], 0xDEADBEEFu) << "wrote past count";
  }
}

// sortbench's host anchor (host/sort/host_lsd_sort.h) is checked like ours: std::stable_sort's
// keys and values, for every shape and width, on 1, 2 and 3 threads (chunk boundaries move).
TEST(HostLsdSort, MatchesStableSort) {
  for (unsigned bits : kKeyBits)
    for (Shape shape : kShapes)
      for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(33), std::size_t(65537),
                            std::size_t(300007)})
        for (unsigned threads : {1u, 2u, 3u}) {
          const std::string what = fmt::format("host LSD, {} threads: {} keys of {} bits, n = {}", threads, name(shape),
                                               bits, n);
          auto keys64 = make_keys(shape, n, bits, 3000 * bits + n + static_cast<int>(shape));
          std::vector<std::uint32_t> values(n), expected_values(n);
          std::iota(values.begin(), values.end(), 0u);
          std::iota(expected_values.begin(), expected_values.end(), 0u);
          if (bits > 32) {
            std::vector<std::uint64_t> keys = keys64, expected = keys64;
            HostLsdScratch<std::uint64_t> scratch;
            reference_sort(expected, expected_values, {bits, 0});
            host_lsd_sort(keys, values, bits, scratch, threads);
            EXPECT_TRUE(keys == expected) << what;
          } else {
            std::vector<std::uint32_t> keys(keys64.begin(), keys64.end()), expected = keys;
            HostLsdScratch<std::uint32_t> scratch;
            reference_sort(expected, expected_values, {bits, 0});
            host_lsd_sort(keys, values, bits, scratch, threads);
            EXPECT_TRUE(keys == expected) << what;
          }
          EXPECT_TRUE(values == expected_values) << what << ": values differ (not stable?)";
        }
}

TEST(Sort, RejectsBadInput) {
  auto& sorter = *device().cpu_shape;
  std::vector<std::uint32_t> k(10), v(10);
  std::vector<std::uint64_t> k64(10);
  EXPECT_THROW(sorter.sort(k, v, {0, 0}), Error);
  EXPECT_THROW(sorter.sort(k, v, {32, 33}), Error);
  EXPECT_THROW(sorter.sort(k64, v, {32, 0}), Error);  // 64-bit keys for a 32-bit config
  std::vector<std::uint32_t> short_v(9);
  EXPECT_THROW(sorter.sort(k, short_v, {32, 0}), Error);
}

// The permute access mode's kernel (cl/permute.cl) equals its host twin, bit for bit, for counts
// around the work-group size, and writes nothing past count.
TEST(Permute, DeviceEqualsHost) {
  Runtime& rt = *device().rt;
  RayPermuter permuter(rt);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> f(-100.0f, 100.0f);
  for (std::uint32_t n : {0u, 1u, 63u, 64u, 65u, 1000u}) {
    std::vector<RsRay> rays(n);
    for (auto& r : rays) r = {{f(rng), f(rng), f(rng)}, f(rng), {f(rng), f(rng), f(rng)}, f(rng)};
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), rng);
    cl::Buffer in = rt.upload("rays", rays);
    cl::Buffer ord = rt.upload("order", order);
    const std::size_t capacity = n + 1;
    std::vector<RsRay> sentinel(capacity);
    sentinel.back().tmax = 12345.0f;
    cl::Buffer out = rt.upload("permuted", sentinel, CL_MEM_READ_WRITE);
    cl::Event ev = permuter.enqueue(in, ord, n, out);
    ev.wait();
    std::vector<RsRay> got;
    rt.download("permuted", out, got, capacity);
    const std::vector<RsRay> want = permute_on_host(rays, order);
    EXPECT_EQ(std::memcmp(got.data(), want.data(), n * sizeof(RsRay)), 0) << n;
    EXPECT_EQ(got.back().tmax, 12345.0f) << "wrote past count, n = " << n;
  }
  EXPECT_THROW(permute_on_host(std::vector<RsRay>(2), {0, 2}), Error);
}

}  // namespace
}  // namespace raysort

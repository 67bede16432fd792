// raysort sortcheck: the radix sort against its host twin (reference_sort) at a few given sizes,
// in the shape this device gets or in one forced by the options. Small and quick on purpose: it is
// what scripts/oclgrind-check.sh runs under Oclgrind's race and memory checks, where sortbench's
// 2 M pair cases and 256 MiB bandwidth copies would take hours. The check script runs one size per
// process: Oclgrind 21.10's uninitialised-value check misreports buffers created after others were
// released in the same process (docs/trace.md, "Oclgrind").
#include <fmt/format.h>

#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/options.h"
#include "render/frame_memory.h"
#include "runtime/runtime.h"
#include "sort/radix_sort.h"

namespace raysort {

namespace {

struct SortCheckOptions {
  std::string device;
  std::vector<std::size_t> sizes = {1, 255, 256, 257, 4097};
  std::vector<unsigned> bits = {32, 64};
  // 0: keep the value RadixSortTuning::for_device gives (the device's own shape).
  unsigned work_group = 0, items = 0, radix_bits = 0, scan_work_group = 0;
  bool onesweep = false;  // force the Onesweep passes (GPU shape)
};

// One size and key width: random keys (fixed seed), sorted on the device and by the host twin.
template <class Key>
bool check_case(RadixSort& sorter, std::size_t n, unsigned bits) {
  std::mt19937_64 rng(n * 977 + bits);
  std::vector<Key> keys(n), want_keys;
  for (auto& k : keys) k = static_cast<Key>(rng());
  std::vector<std::uint32_t> values(n), want_values;
  std::iota(values.begin(), values.end(), 0u);
  const RadixSortConfig cfg{bits, 0};
  want_keys = keys;
  want_values = values;
  reference_sort(want_keys, want_values, cfg);
  SortStats s = sorter.sort(keys, values, cfg);
  const bool ok = keys == want_keys && values == want_values;
  fmt::print("  n {:>6}  {}-bit keys  passes {}/{} run/skipped  {}\n", n, bits, s.passes_run, s.passes_skipped,
             ok ? "ok" : "DIFFERS from the host twin");
  return ok;
}

void run_sortcheck(const SortCheckOptions& opt) {
  Runtime rt(select_device(opt.device));
  RadixSortTuning t = RadixSortTuning::for_device(rt.info());
  if (opt.work_group) t.work_group = opt.work_group;
  if (opt.items) t.items = opt.items;
  if (opt.radix_bits) t.radix_bits = opt.radix_bits;
  if (opt.scan_work_group) t.scan_work_group = opt.scan_work_group;
  if (opt.onesweep) t.onesweep = true;
  // The pairs, their host twin's copies and the device's buffers, before any is allocated.
  for (unsigned bits : opt.bits)
    for (std::size_t n : opt.sizes)
      check_sort_memory(n, bits > 32 ? 8 : 4, &rt.info(),
                        fmt::format("sortcheck of {} pairs with {}-bit keys", n, bits > 32 ? 64 : 32), "lower --sizes");
  RadixSort sorter(rt, t);
  fmt::print("device: {} ({})\nradix sort: {}-bit digits, work-group {}, {} keys per work-item, scan work-group {}, {}\n",
             rt.info().name, rt.info().platform_name, t.radix_bits, t.work_group, t.items, t.scan_work_group,
             t.work_group == 1 ? std::string("CPU shape") : fmt::format("{} passes", t.gpu_passes()));
  bool all_ok = true;
  for (unsigned bits : opt.bits)
    for (std::size_t n : opt.sizes)
      all_ok = (bits > 32 ? check_case<std::uint64_t>(sorter, n, bits) : check_case<std::uint32_t>(sorter, n, bits)) &&
               all_ok;
  if (!all_ok) {
    fmt::print("FAILED: a sorted result differs from the host twin\n");
    set_command_exit_code(1);
  }
}

}  // namespace

void register_sortcheck_command(CLI::App& app) {
  static SortCheckOptions opt;
  auto* cmd = app.add_subcommand("sortcheck", "check the radix sort against its host twin at a few sizes (any shape)");
  cmd->add_option("--device", opt.device, "OpenCL device: index, cpu, gpu or a name substring");
  // At most the 2^32 - 1 pairs the sort's 32-bit positions address; the memory they take is
  // checked against the machine once the device is known (check_sort_memory).
  whole_number(cmd->add_option("--sizes", opt.sizes, "comma-separated pair counts")->delimiter(',')->capture_default_str(),
               1, std::numeric_limits<std::uint32_t>::max());
  whole_number(cmd->add_option("--bits", opt.bits, "comma-separated key widths (1..64)")->delimiter(',')->capture_default_str(),
               1, 64);
  // 0 keeps the device's own value; a shape the device cannot run is refused by RadixSort.
  whole_number(cmd->add_option("--work-group", opt.work_group,
                               "force the tile's work-items (1: the CPU shape; > 1: the GPU shape; a power of two)"),
               0, 65536);
  whole_number(cmd->add_option("--items", opt.items, "force keys per work-item (GPU shape)"), 0, 65536);
  whole_number(cmd->add_option("--radix-bits", opt.radix_bits, "force the digit width (1 to 12)"), 0, 12);
  whole_number(cmd->add_option("--scan-work-group", opt.scan_work_group, "force the scan's work-items (a power of two)"), 0,
               65536);
  cmd->add_flag("--onesweep", opt.onesweep,
                "force the Onesweep passes (decoupled look-back; the GPU shape, a work-group of 2 or more)");
  cmd->callback([] { run_sortcheck(opt); });
}

}  // namespace raysort

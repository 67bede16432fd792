#pragma once
// Our own LSD radix sort on an OpenCL device (kernels: cl/radix_sort.cl, which documents the
// method): stable (key, value) pairs, 32- or 64-bit keys, 32-bit values (ray indices), any count.
// Only the bits a key uses are sorted, passes whose digit is the same for every key are skipped,
// and a "top k bits" mode sorts by the highest k bits only.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace raysort {

struct RadixSortConfig {
  // Bits the key uses, counted from bit 0: keys of up to 32 bits live in uint32 buffers, wider
  // ones in uint64 buffers. Bits above key_bits are ignored. 16, 32 and 64 are the suite's widths.
  unsigned key_bits = 32;
  // 0: sort by all key_bits. k > 0: sort by the highest k of them, bits [key_bits - k, key_bits),
  // keeping the input order among keys that agree there (cheaper, less ordered).
  unsigned top_bits = 0;
  // 0: a full sort. g > 0: the sort that stops at warp granularity (paper, "Application in Faster
  // Tracing Kernels"; docs/sort.md): a most-significant-digit-first bucket sort by 8-bit digits
  // that splits a range only while it holds more than g pairs; a range of g pairs or fewer keeps
  // its input order. Every pair ends fewer than g places from where the full sort puts it. The
  // CPU shape only (one work-item per tile, 8-bit digits); reference_warp_sort is its host twin.
  unsigned warp_group = 0;

  bool wide_keys() const { return key_bits > 32; }
  std::size_t key_bytes() const { return wide_keys() ? 8 : 4; }
  unsigned sorted_bits() const { return top_bits == 0 ? key_bits : top_bits; }
  unsigned lo_bit() const { return key_bits - sorted_bits(); }
};

// One kind of command of a sort (a kernel by its name, a read-back, the final copy): how often it
// ran and its summed device time (profiling events). The commands' times add up to kernel_ms.
struct SortCommandTime {
  std::string name;
  unsigned launches = 0;
  double ms = 0.0;
};

struct SortStats {
  std::size_t count = 0;
  // Counting-sort passes executed (the warp-granular sort: its global pass and its walk, 2).
  unsigned passes_run = 0;
  unsigned passes_skipped = 0;  // passes whose digit is the same for every key
  double ms = 0.0;              // profiling events: first command's start to last command's end
  double kernel_ms = 0.0;       // sum of the commands' own durations (no gaps, no host read-back)
  std::vector<SortCommandTime> commands;  // kernel_ms by command, in the order each first ran
  double mkeys_per_s() const { return ms > 0.0 ? static_cast<double>(count) / ms * 1e-3 : 0.0; }
};

// The shape of the kernels on one device. for_device() derives it from the device's limits; tests
// force other shapes to cover both kernel paths on one device.
struct RadixSortTuning {
  unsigned radix_bits = 8;  // digit width: 2^radix_bits buckets per pass
  // Work-items per tile. 1: a tile is one serial chunk (CPUs). > 1: ranked in local memory (GPUs).
  unsigned work_group = 1;
  unsigned items = 8;             // work_group > 1: keys per work-item, staged in local memory
  unsigned tiles_per_unit = 16;   // work_group == 1: tiles per compute unit (tile size follows N)
  unsigned min_tile = 4096;       // work_group == 1: smallest tile, in keys
  unsigned scan_work_group = 1;   // work-items of the single-group scan (a power of two)
  unsigned reduce_work_group = 64;
  // work_group == 1 and radix_bits <= 8: from this many pairs on (0: never), an MSD-first hybrid.
  // One global counting pass on the most significant varying digit splits the pairs into buckets,
  // then each bucket is sorted by the lower digits with LSD passes while it sits in cache. Falls
  // back to the global LSD passes when one bucket holds more than 1 / hybrid_skew of the pairs.
  std::size_t hybrid_min = std::size_t(1) << 20;
  unsigned hybrid_skew = 4;
  // work_group > 1: every pass as one Onesweep kernel (cl/radix_sort.cl: one read for the
  // histograms of all passes, then per pass a decoupled look-back instead of count + scan +
  // scatter). It assumes forward progress between work-groups, which OpenCL does not promise:
  // for_device turns it on for NVIDIA's GPUs only; tests force it on PoCL and Oclgrind, whose
  // work-groups run to completion. Sorts of 2^30 pairs or more take the reduce-then-scan passes.
  bool onesweep = false;

  bool hybrid() const { return work_group == 1 && radix_bits <= 8 && hybrid_min > 0; }
  // Passes a key of key_bits bits can take: ceil(key_bits / radix_bits) (cl/radix_sort.cl's RS_MAX_PASSES).
  unsigned max_passes(unsigned key_bits) const { return (key_bits + radix_bits - 1) / radix_bits; }
  // The GPU shape's kind of passes, as sortbench, sortcheck and the docs name it.
  const char* gpu_passes() const { return onesweep ? "Onesweep" : "reduce-then-scan"; }

  static RadixSortTuning for_device(const DeviceInfo& device);
  // Local memory one tile of the scatter kernel needs (the largest of the kernels).
  std::size_t local_bytes(std::size_t key_bytes) const;
};

// What a tuning does when a kernel takes fewer work-items per group on the device than the tuning
// launches it with (CL_KERNEL_WORK_GROUP_SIZE, below the device's maximum where the kernel needs
// many registers): a forced tuning is refused (Exact); the device's own shrinks that launch to the
// largest power of two the kernel takes and builds again (ShrinkToKernels).
enum class RadixSortFit { Exact, ShrinkToKernels };

class RadixSort {
 public:
  // Builds the 32- and 64-bit key programs once, shaped by RadixSortTuning::for_device and fitted
  // to what each kernel takes on the device (RadixSortFit::ShrinkToKernels).
  explicit RadixSort(Runtime& rt);
  RadixSort(Runtime& rt, const RadixSortTuning& tuning, RadixSortFit fit = RadixSortFit::Exact);

  // Sorts `count` pairs in place: `keys` holds uint32 (cfg.key_bits <= 32) or uint64 keys,
  // `values` uint32. Stable. Blocks until done: after the first read of the keys it reads back
  // which digits vary (one 16-byte read) to choose the passes. Scratch buffers only grow.
  SortStats sort(cl::Buffer& keys, cl::Buffer& values, std::size_t count, const RadixSortConfig& cfg = {});

  // Host vectors in, sorted vectors out (through device buffers that are kept and only grow).
  SortStats sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg = {});
  SortStats sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg = {});

  // Runs every kernel once on a small input (both key widths), so that a device compiling kernels
  // at their first launch (PoCL) does so outside the timed part. Returns its wall-clock ms.
  double warm_up();

  const RadixSortTuning& tuning() const { return tuning_; }
  // Whether this shape runs RadixSortConfig::warp_group > 0 (one work-item per tile, 8-bit digits).
  bool warp_sort_shape() const { return tuning_.work_group == 1 && tuning_.radix_bits == 8; }
  // Passes a sort with cfg takes before skipping: ceil(sorted_bits / radix_bits).
  unsigned passes(const RadixSortConfig& cfg) const;

 private:
  struct Kernels {
    cl::Kernel count_bounds, reduce_bounds, count, scan, scatter;
    cl::Kernel bucket_sort;  // the hybrid's per-bucket LSD passes (work_group == 1 only)
    cl::Kernel warp_sort;    // the warp-granular sort's per-bucket walk (warp_sort_shape() only)
    cl::Kernel sweep_clear, hist_all, hist_scan, onesweep;  // the Onesweep passes (tuning.onesweep only)
  };
  Kernels& kernels_for(const RadixSortConfig& cfg) { return cfg.wide_keys() ? wide_ : narrow_; }
  // The first launch whose work-group is more than its kernel takes on the device.
  struct KernelOverflow {
    const char* name;
    unsigned local;
    std::size_t most;
    bool scan_shape;  // a launch of scan_work_group (else work_group)
  };
  std::optional<KernelOverflow> build_kernels(Runtime& rt);
  // Launches kernel k (its function name: what SortStats::commands counts it as).
  void enqueue(cl::Kernel& k, const char* name, std::size_t global, std::size_t local);
  // A new profiling event for a command of kind `name`, a string literal (SortStats::commands).
  cl::Event& record(const char* name);
  struct Passes;  // one sort's launches and ping-pong buffers (radix_sort.cpp)
  std::uint64_t first_read(Kernels& k, const cl::Buffer& keys, cl_uint n, cl_uint n_items, cl_uint shift, cl_uint hi,
                           std::size_t tiles, std::size_t key_bytes);
  bool hybrid_passes(Passes& ps, const std::vector<unsigned>& run, int counted, cl_uint lo, std::size_t count);
  void warp_passes(Passes& ps, const std::vector<unsigned>& run, int counted, cl_uint lo, unsigned group);
  void onesweep_passes(Passes& ps, const std::vector<unsigned>& run, cl_uint lo, unsigned key_width);
  static void ensure(Runtime& rt, cl::Buffer& b, std::size_t& have, std::size_t need, const char* name);
  template <class Key>
  SortStats sort_host(std::vector<Key>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg);

  Runtime& rt_;
  RadixSortTuning tuning_;
  Kernels narrow_, wide_;
  // Scratch, grown on demand: ping-pong keys/values, per-tile digit counts, per-tile key OR/AND
  // and their reduction, Onesweep's digit positions, tile counters and look-back status.
  cl::Buffer keys_tmp_, values_tmp_, counts_, tile_bounds_, bounds_, sweep_;
  std::size_t keys_tmp_bytes_ = 0, values_tmp_bytes_ = 0, counts_bytes_ = 0, tile_bounds_bytes_ = 0, bounds_bytes_ = 0,
              sweep_bytes_ = 0;
  // Device copies for the host-vector overloads.
  cl::Buffer keys_io_, values_io_;
  std::size_t keys_io_bytes_ = 0, values_io_bytes_ = 0;
  std::vector<cl::Event> events_;
  std::vector<const char*> event_names_;  // each event's command (SortCommandTime::name)
  std::vector<std::uint32_t> bucket_offsets_;
};

// The host twin: std::stable_sort of the pairs by the bits cfg sorts on. The device sort must give
// exactly these keys and values.
template <class Key>
void reference_sort(std::vector<Key>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg) {
  const unsigned lo = cfg.lo_bit();
  const unsigned bits = cfg.sorted_bits();
  const Key mask = bits >= 64 ? ~Key(0) : static_cast<Key>((std::uint64_t(1) << bits) - 1);
  struct Pair {
    Key key;
    std::uint32_t value;
  };
  std::vector<Pair> pairs(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) pairs[i] = {keys[i], values[i]};
  std::stable_sort(pairs.begin(), pairs.end(),
                   [&](const Pair& a, const Pair& b) { return ((a.key >> lo) & mask) < ((b.key >> lo) & mask); });
  for (std::size_t i = 0; i < keys.size(); ++i) {
    keys[i] = pairs[i].key;
    values[i] = pairs[i].value;
  }
}

// The host twin of the warp-granular sort (cfg.warp_group > 0, see RadixSortConfig): split a
// range stably by its next 8-bit digit, from the top of the sorted bits down, while it holds more
// than cfg.warp_group pairs.
template <class Key>
void reference_warp_sort(std::vector<Key>& keys, std::vector<std::uint32_t>& values, const RadixSortConfig& cfg) {
  struct Pair {
    Key key;
    std::uint32_t value;
  };
  std::vector<Pair> pairs(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) pairs[i] = {keys[i], values[i]};
  const unsigned lo = cfg.lo_bit(), hi = cfg.key_bits;
  auto digit = [&](Key key, unsigned p) {
    const unsigned shift = lo + 8 * p, width = std::min(8u, hi - shift);
    return static_cast<unsigned>(key >> shift) & ((1u << width) - 1);
  };
  auto split = [&](auto& self, std::size_t b, std::size_t e, unsigned p) -> void {
    if (e - b <= cfg.warp_group) return;  // a warp's worth or less: input order
    std::stable_sort(pairs.begin() + b, pairs.begin() + e,
                     [&](const Pair& x, const Pair& y) { return digit(x.key, p) < digit(y.key, p); });
    if (p == 0) return;
    for (std::size_t i = b; i < e;) {
      std::size_t j = i;
      while (j < e && digit(pairs[j].key, p) == digit(pairs[i].key, p)) ++j;
      self(self, i, j, p - 1);
      i = j;
    }
  };
  if (!pairs.empty()) split(split, 0, pairs.size(), (cfg.sorted_bits() + 7) / 8 - 1);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    keys[i] = pairs[i].key;
    values[i] = pairs[i].value;
  }
}

}  // namespace raysort

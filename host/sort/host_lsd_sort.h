#pragma once
// The host anchor of `raysort sortbench`: a plain least-significant-digit radix sort of (key,
// value) pairs on the host's threads, 8-bit digits, stable. It is what a user gets from a
// 60-line C++ program (issue 42), so our OpenCL sort is measured against it on the same keys.
// Each thread owns one contiguous chunk; a pass counts every chunk's digits, turns the counts
// into per-(digit, chunk) start positions, and every thread writes its chunk in order, so a pass
// is stable for any thread count. A pass whose digit is the same for every key is skipped.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace raysort {

struct HostLsdStats {
  unsigned passes_run = 0;
  unsigned passes_skipped = 0;
};

// The ping-pong buffers, kept between calls so that a timed sort does not pay for fresh pages
// (our device sort keeps its scratch buffers too).
template <class Key>
struct HostLsdScratch {
  std::vector<Key> keys;
  std::vector<std::uint32_t> values;
};

// Sorts keys[i] with values[i] by the low `key_bits` bits of the key (stable). `threads` 0: the
// host's (host/util/parallel.h).
HostLsdStats host_lsd_sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                           HostLsdScratch<std::uint32_t>& scratch, unsigned threads = 0);
HostLsdStats host_lsd_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                           HostLsdScratch<std::uint64_t>& scratch, unsigned threads = 0);

}  // namespace raysort

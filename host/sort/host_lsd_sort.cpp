#include "sort/host_lsd_sort.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <thread>

#include "util/error.h"
#include "util/parallel.h"

namespace raysort {

namespace {

constexpr unsigned kDigitBits = 8;
constexpr std::size_t kRadix = std::size_t(1) << kDigitBits;
using Histogram = std::array<std::size_t, kRadix>;

// Runs work(t, begin, end) for every chunk t of [0, n), one thread per chunk.
template <class Work>
void on_chunks(std::size_t n, unsigned threads, Work&& work) {
  const std::size_t chunk = (n + threads - 1) / threads;
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t)
    pool.emplace_back([&work, t, chunk, n] { work(t, std::min(n, t * chunk), std::min(n, (t + 1) * chunk)); });
  work(0u, std::size_t{0}, std::min(n, chunk));
  for (auto& th : pool) th.join();
}

template <class Key>
HostLsdStats lsd_sort(std::vector<Key>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                      HostLsdScratch<Key>& scratch, unsigned threads) {
  if (keys.size() != values.size())
    throw Error(fmt::format("host LSD sort: {} keys but {} values", keys.size(), values.size()));
  if (key_bits < 1 || key_bits > 8 * sizeof(Key))
    throw Error(fmt::format("host LSD sort: key_bits {} on {}-byte keys", key_bits, sizeof(Key)));
  const std::size_t n = keys.size();
  if (threads == 0) threads = host_threads();
  // Small inputs on one thread: a thread start costs more than the chunk.
  threads = static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(threads, n / 65536)));
  if (scratch.keys.size() < n) scratch.keys.resize(n);
  if (scratch.values.size() < n) scratch.values.resize(n);
  Key* src_k = keys.data();
  Key* dst_k = scratch.keys.data();
  std::uint32_t* src_v = values.data();
  std::uint32_t* dst_v = scratch.values.data();
  std::vector<Histogram> counts(threads);
  HostLsdStats stats;
  for (unsigned shift = 0; shift < key_bits; shift += kDigitBits) {
    const Key mask = static_cast<Key>((std::uint64_t(1) << std::min(kDigitBits, key_bits - shift)) - 1);
    on_chunks(n, threads, [&](unsigned t, std::size_t b, std::size_t e) {
      Histogram& h = counts[t];
      h.fill(0);
      for (std::size_t i = b; i < e; ++i) ++h[(src_k[i] >> shift) & mask];
    });
    // Digit-major, chunk-minor: chunk t's keys of digit d go after every earlier chunk's.
    std::size_t running = 0;
    bool constant = false;
    for (std::size_t d = 0; d < kRadix; ++d) {
      std::size_t digit_total = 0;
      for (unsigned t = 0; t < threads; ++t) {
        const std::size_t c = counts[t][d];
        counts[t][d] = running;
        running += c;
        digit_total += c;
      }
      constant = constant || digit_total == n;
    }
    if (constant) {  // one bin holds every key: this pass would not move anything
      ++stats.passes_skipped;
      continue;
    }
    on_chunks(n, threads, [&](unsigned t, std::size_t b, std::size_t e) {
      Histogram& position = counts[t];
      for (std::size_t i = b; i < e; ++i) {
        const std::size_t to = position[(src_k[i] >> shift) & mask]++;
        dst_k[to] = src_k[i];
        dst_v[to] = src_v[i];
      }
    });
    std::swap(src_k, dst_k);
    std::swap(src_v, dst_v);
    ++stats.passes_run;
  }
  if (src_k != keys.data()) {  // an odd number of passes ran: the result is in the scratch vectors
    std::copy(src_k, src_k + n, keys.begin());
    std::copy(src_v, src_v + n, values.begin());
  }
  return stats;
}

}  // namespace

HostLsdStats host_lsd_sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                           HostLsdScratch<std::uint32_t>& scratch, unsigned threads) {
  return lsd_sort(keys, values, key_bits, scratch, threads);
}

HostLsdStats host_lsd_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                           HostLsdScratch<std::uint64_t>& scratch, unsigned threads) {
  return lsd_sort(keys, values, key_bits, scratch, threads);
}

}  // namespace raysort

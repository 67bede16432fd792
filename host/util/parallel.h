#pragma once
// Host work split into one contiguous chunk per thread: the host twins and the host encoders run
// the same per-item code on every core, and the items are independent, so any split gives the
// same results.
#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace raysort {

// The threads the host splits work over: the hardware's, at most 16.
inline unsigned host_threads() { return std::max(1u, std::min(16u, std::thread::hardware_concurrency())); }

// Runs work(begin, end) over [0, n): in this thread when `serial` (an input too small for threads
// to pay) or the host has one thread, else one contiguous chunk per host thread.
template <class Work>
void for_each_chunk(std::size_t n, bool serial, Work&& work) {
  const unsigned threads = host_threads();
  if (serial || threads == 1) {
    work(std::size_t{0}, n);
    return;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (n + threads - 1) / threads;
  for (unsigned t = 0; t < threads; ++t) {
    const std::size_t b = t * chunk, e = std::min(n, b + chunk);
    if (b < e) pool.emplace_back([&work, b, e] { work(b, e); });
  }
  for (auto& th : pool) th.join();
}

}  // namespace raysort

#pragma once
// Host work spread over threads. for_each_chunk: one contiguous chunk per thread (the host twins
// and the host encoders run the same per-item code on every core, and the items are independent,
// so any split gives the same results). for_each_job: jobs of uneven size (the BVH builder's
// subtrees), each thread taking the next job when its last is done; every job writes only its
// own outputs, so which thread ran which job never shows in the result.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace raysort {

// The threads the host splits work over: the hardware's, at most 16.
inline unsigned host_threads() { return std::max(1u, std::min(16u, std::thread::hardware_concurrency())); }

// Runs work(begin, end) over [0, n) in one contiguous chunk per thread on `threads` threads (this
// one among them); in this thread alone when threads <= 1.
template <class Work>
void for_each_chunk_on(unsigned threads, std::size_t n, Work&& work) {
  if (threads <= 1) {
    work(std::size_t{0}, n);
    return;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (n + threads - 1) / threads;
  for (unsigned t = 1; t < threads; ++t) {
    const std::size_t b = t * chunk, e = std::min(n, b + chunk);
    if (b < e) pool.emplace_back([&work, b, e] { work(b, e); });
  }
  if (n > 0) work(std::size_t{0}, std::min(n, chunk));
  for (auto& th : pool) th.join();
}

// Runs work(begin, end) over [0, n): in this thread when `serial` (an input too small for threads
// to pay) or the host has one thread, else one contiguous chunk per host thread.
template <class Work>
void for_each_chunk(std::size_t n, bool serial, Work&& work) {
  for_each_chunk_on(serial ? 1u : host_threads(), n, std::forward<Work>(work));
}

// Runs job(i) for every i in [0, n) on `threads` threads (this one among them), each taking the
// lowest job not yet taken. The first exception a job throws is rethrown here once all threads
// have stopped (the others take no new jobs after it).
template <class Job>
void for_each_job(unsigned threads, std::size_t n, Job&& job) {
  threads = static_cast<unsigned>(std::min<std::size_t>(std::max(1u, threads), n));
  if (threads <= 1) {
    for (std::size_t i = 0; i < n; ++i) job(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        job(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next.store(n);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace raysort

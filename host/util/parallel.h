#pragma once
// Host work spread over threads. for_each_chunk: one contiguous chunk per thread (the BVH
// builder's binning, whose per-chunk partial results follow the split). for_each_block: blocks
// taken by whichever thread is free (the host twins and the host encoders run the same per-item
// code on every core, and the items are independent, so any split gives the same results).
// for_each_job: jobs of uneven size (the BVH builder's subtrees), each thread taking the next job
// when its last is done; every job writes only its own outputs, so which thread ran which job never
// shows in the result. JobStream: the same for jobs that appear while the threads already run the
// first ones (the BVH builder's subtrees, made by the splits of the top of the tree).
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
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

// Runs work(worker, begin, end) over [0, n) in blocks of `block` items on `threads` threads (this
// one, worker 0, among them), each thread taking the next block when its last is done. For items of
// uneven cost (a frame's rays: the sky's take no step, a wall's take dozens), where one contiguous
// chunk per thread leaves a core idle once its half is done. `worker` < threads names the thread, for
// per-thread partial results that are summed afterwards (any split gives the same sums). The first
// exception a block throws is rethrown here once all threads have stopped (as for_each_job).
template <class Work>
void for_each_block_on(unsigned threads, std::size_t n, std::size_t block, Work&& work) {
  block = std::max<std::size_t>(1, block);
  const std::size_t blocks = (n + block - 1) / block;
  threads = static_cast<unsigned>(std::min<std::size_t>(std::max(1u, threads), std::max<std::size_t>(1, blocks)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&](unsigned w) {
    for (std::size_t b; (b = next.fetch_add(1)) < blocks;) {
      try {
        work(w, b * block, std::min(n, (b + 1) * block));
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next.store(blocks);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);
}

// Runs work(begin, end) over [0, n) in blocks of `block` items, balanced over the host's threads
// (for_each_block_on); in this thread alone when `serial`.
template <class Work>
void for_each_block(std::size_t n, bool serial, Work&& work, std::size_t block = 1024) {
  for_each_block_on(serial ? 1u : host_threads(), n, block,
                    [&work](unsigned, std::size_t b, std::size_t e) { work(b, e); });
}

// Runs job(i) for every i in [0, n) on `threads` threads (this one among them), each taking the
// lowest job not yet taken: blocks of one job (for_each_block_on). The first exception a job throws
// is rethrown here once all threads have stopped (the others take no new jobs after it).
template <class Job>
void for_each_job(unsigned threads, std::size_t n, Job&& job) {
  for_each_block_on(threads, n, 1, [&job](unsigned, std::size_t i, std::size_t) { job(i); });
}

// Jobs run by `threads` - 1 workers as they are added, and by this thread too from finish() on:
// each thread takes the largest pending job (the last to start is then small, so the threads
// finish together). A job may add jobs. finish() returns when every job added has run, and
// rethrows the first exception a job threw (no job starts after it). Destroying a stream without finish() (the
// producer threw) drops the pending jobs and waits for the running ones.
class JobStream {
 public:
  explicit JobStream(unsigned threads) {
    for (unsigned t = 1; t < threads; ++t) workers_.emplace_back([this] { work(); });
  }
  JobStream(const JobStream&) = delete;
  JobStream& operator=(const JobStream&) = delete;
  ~JobStream() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
      pending_.clear();
    }
    join();
  }

  void add(std::uint64_t size, std::function<void()> job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (failure_) return;
      pending_.push_back({size, added_++, std::move(job)});
    }
    ready_.notify_one();
  }

  void finish() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
    work();
    join();
    if (failure_) std::rethrow_exception(failure_);
  }

 private:
  struct Pending {
    std::uint64_t size, order;
    std::function<void()> job;
  };

  void work() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        // Pending jobs, or closed with none running (a running job may still add some).
        ready_.wait(lock, [this] { return !pending_.empty() || (closed_ && running_ == 0); });
        if (pending_.empty()) return;
        auto largest = std::min_element(pending_.begin(), pending_.end(), [](const Pending& a, const Pending& b) {
          return a.size != b.size ? a.size > b.size : a.order < b.order;
        });
        job = std::move(largest->job);
        pending_.erase(largest);
        ++running_;
      }
      try {
        job();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!failure_) failure_ = std::current_exception();
        pending_.clear();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        --running_;
      }
      ready_.notify_all();
    }
  }

  void join() {
    ready_.notify_all();
    for (auto& th : workers_) th.join();
    workers_.clear();
  }

  std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<Pending> pending_;
  std::uint64_t added_ = 0;
  std::size_t running_ = 0;
  bool closed_ = false;
  std::exception_ptr failure_;
  std::vector<std::thread> workers_;
};

}  // namespace raysort

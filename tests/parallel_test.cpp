// Host work spread over threads (util/parallel.h): every item runs once, whatever the split, and
// uneven items are shared out rather than left to one thread.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <stdexcept>
#include <thread>
#include <vector>

#include "util/parallel.h"

namespace raysort {

TEST(Parallel, ForEachBlockRunsEveryItemOnceForAnySplit) {
  for (unsigned threads : {1u, 2u, 3u, 8u})
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{1023}, std::size_t{1024}, std::size_t{5000}})
      for (std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{1024}, std::size_t{100000}}) {
        std::vector<std::atomic<int>> runs(n);
        std::atomic<unsigned> bad_worker{0};
        for_each_block_on(threads, n, block, [&](unsigned worker, std::size_t begin, std::size_t end) {
          if (worker >= threads || end - begin > block || begin >= end) ++bad_worker;
          for (std::size_t i = begin; i < end; ++i) ++runs[i];
        });
        EXPECT_EQ(bad_worker.load(), 0u) << threads << " threads, " << n << " items, blocks of " << block;
        for (std::size_t i = 0; i < n; ++i)
          ASSERT_EQ(runs[i].load(), 1) << "item " << i << ": " << threads << " threads, " << n << " items, blocks of "
                                       << block;
      }
}

TEST(Parallel, ForEachBlockSharesUnevenWorkBetweenThreads) {
  // The first half of the items is slow (as the rays of a frame's lower half, which hit walls, where
  // the upper half's leave through the sky). One contiguous chunk per thread gives all of it to one
  // thread; with blocks, the other thread takes slow items while the first is busy. Item 0 stays
  // busy until another thread has run an item of the first half (or 20 s have passed).
  const std::size_t n = 64;
  std::vector<std::atomic<int>> ran_by(n);
  for (auto& r : ran_by) r = -1;
  bool shared = false;
  for_each_block_on(2, n, 1, [&](unsigned worker, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      ran_by[i] = static_cast<int>(worker);
      if (i != 0) continue;
      auto other_ran_a_slow_item = [&] {
        for (std::size_t k = 1; k < n / 2; ++k)
          if (ran_by[k] >= 0 && ran_by[k] != static_cast<int>(worker)) return true;
        return false;
      };
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (!(shared = other_ran_a_slow_item()) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  EXPECT_TRUE(shared) << "no other thread ran an item of the first half while item 0 was busy";
}

TEST(Parallel, ForEachBlockRethrowsABlocksException) {
  // A block that throws on a worker thread must fail the call, not terminate the process.
  for (unsigned threads : {1u, 2u, 4u}) {
    std::atomic<std::size_t> ran{0};
    EXPECT_THROW(for_each_block_on(threads, 1000, 10,
                                   [&](unsigned, std::size_t begin, std::size_t) {
                                     ++ran;
                                     if (begin == 500) throw std::runtime_error("block 50");
                                   }),
                 std::runtime_error)
        << threads << " threads";
    EXPECT_LE(ran.load(), std::size_t{100});
  }
}

}  // namespace raysort

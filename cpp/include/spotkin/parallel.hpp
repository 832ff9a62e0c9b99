// Splitting a batch of independent samples across threads.
//
// Every sample is computed by the same code whatever the split, so results are
// bit-identical for any thread count. Batches below `kMinSamplesPerThread` per
// extra thread stay on the calling thread.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <thread>
#include <vector>

namespace spotkin {

inline std::atomic<int>& num_threads_setting() noexcept {
  static std::atomic<int> value{[] {
    if (const char* env = std::getenv("SPOTKIN_NUM_THREADS")) {
      const int n = std::atoi(env);
      if (n > 0) return n;
    }
    const unsigned hw = std::thread::hardware_concurrency();
    return hw == 0 ? 1 : static_cast<int>(hw);
  }()};
  return value;
}

inline int get_num_threads() noexcept { return num_threads_setting().load(); }
inline void set_num_threads(int n) noexcept { num_threads_setting().store(std::max(1, n)); }

// Calls body(begin, end) over [0, n) in contiguous chunks. `min_per_thread` is
// the smallest chunk worth a thread. Measured on the 2-core development
// machine: spawning and joining a thread costs about 17 us, so a chunk should
// hold at least ~200 us of work; each kernel's threshold is 200 us divided by
// its measured single-thread cost per sample (kChunkWork below).
// Chunks start at multiples of kChunkAlignment, a multiple of every kernel's
// block size, so each sample goes through the same code path (vector body or
// remainder loop) whatever the thread count or split: results are bit-identical.
constexpr std::ptrdiff_t kChunkAlignment = 64;

// Smallest chunk for a kernel costing `ns_per_sample` on one thread.
constexpr std::ptrdiff_t min_chunk(double ns_per_sample) {
  constexpr double kChunkWork = 200e3;  // ns: over 10x the spawn cost
  return static_cast<std::ptrdiff_t>(kChunkWork / ns_per_sample);
}

template <typename Body>
void parallel_for(std::ptrdiff_t n, std::ptrdiff_t min_per_thread, Body&& body) {
  const std::ptrdiff_t by_size = min_per_thread > 0 ? n / min_per_thread : n;
  const std::ptrdiff_t threads =
      std::max<std::ptrdiff_t>(1, std::min<std::ptrdiff_t>(get_num_threads(), by_size));
  if (threads <= 1) {
    body(std::ptrdiff_t{0}, n);
    return;
  }
  // Chunks are handed out from a shared counter, about 8 per thread, so a core
  // that runs faster (cores of a VM often differ) takes more of the batch
  // instead of waiting for the slowest; each chunk starts on a block boundary.
  std::ptrdiff_t grain = std::max<std::ptrdiff_t>(min_per_thread / 4, n / (8 * threads));
  grain = std::max<std::ptrdiff_t>(1, (grain + kChunkAlignment - 1) / kChunkAlignment) * kChunkAlignment;
  std::atomic<std::ptrdiff_t> next{0};
  auto work = [&] {
    for (;;) {
      const std::ptrdiff_t begin = next.fetch_add(grain, std::memory_order_relaxed);
      if (begin >= n) return;
      body(begin, std::min(n, begin + grain));
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(static_cast<std::size_t>(threads - 1));
  for (std::ptrdiff_t t = 1; t < threads; ++t) workers.emplace_back(work);
  work();
  for (auto& w : workers) w.join();
}

}  // namespace spotkin

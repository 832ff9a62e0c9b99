// Splitting a batch of independent samples across threads.
//
// Every sample is computed by the same code whatever the split, so results are
// bit-identical for any thread count. Batches below `kMinSamplesPerThread` per
// extra thread stay on the calling thread.
//
// Long batches can be interrupted: the calling thread asks a registered poll
// (the bindings check Python's signals) between its chunks, at most every
// kPollInterval; when it says stop, every thread finishes its current chunk,
// all are joined, and parallel_for throws Interrupted.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdlib>
#include <exception>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace spotkin {

// The most worker threads set_num_threads accepts (SPOTKIN_NUM_THREADS is capped to it).
constexpr int kMaxThreads = 1024;

// The thread count SPOTKIN_NUM_THREADS asks for: 0 when unset, -1 when it is not
// a positive integer, else at most kMaxThreads.
inline int parse_thread_count(const char* text) noexcept {
  if (text == nullptr) return 0;
  char* end = nullptr;
  const long long n = std::strtoll(text, &end, 10);
  while (end && *end == ' ') ++end;
  if (end == text || (end && *end != '\0') || n < 1) return -1;
  return n > kMaxThreads ? kMaxThreads : static_cast<int>(n);
}

inline int default_num_threads() noexcept {
  const int from_env = parse_thread_count(std::getenv("SPOTKIN_NUM_THREADS"));
  if (from_env > 0) return from_env;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(std::min<unsigned>(hw, kMaxThreads));
}

inline std::atomic<int>& num_threads_setting() noexcept {
  static std::atomic<int> value{default_num_threads()};
  return value;
}

// A limit for the calls made from this thread (0: none), under the process-wide
// setting: a caller that already runs its own threads (a Dask worker thread)
// keeps each call from spawning a full set of its own.
inline int& thread_limit() noexcept {
  thread_local int limit = 0;
  return limit;
}

// The threads a call from this thread may use.
inline int get_num_threads() noexcept {
  const int n = num_threads_setting().load();
  const int limit = thread_limit();
  return limit > 0 && limit < n ? limit : n;
}
// Clamped into [1, kMaxThreads]; the bindings reject values outside it first.
inline void set_num_threads(int n) noexcept { num_threads_setting().store(std::clamp(n, 1, kMaxThreads)); }

// Thrown by parallel_for when the poll asked it to stop.
struct Interrupted : std::exception {
  const char* what() const noexcept override { return "interrupted"; }
};

// Returns true when the batch should stop (called on the thread that called parallel_for).
using InterruptPoll = bool (*)() noexcept;
inline std::atomic<InterruptPoll>& interrupt_poll() noexcept {
  static std::atomic<InterruptPoll> poll{nullptr};
  return poll;
}
constexpr std::chrono::milliseconds kPollInterval{5};

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

// A chunk holds at most this many minimum chunks (about 20 ms of work), so an
// interrupt is seen within about that time.
constexpr std::ptrdiff_t kMaxChunksPerGrain = 100;

namespace detail {
inline std::ptrdiff_t align_up(std::ptrdiff_t n, std::ptrdiff_t alignment = kChunkAlignment) {
  return std::max<std::ptrdiff_t>(1, (n + alignment - 1) / alignment) * alignment;
}
}  // namespace detail

// `alignment`: where chunks may start. Samples of a lane kernel keep kChunkAlignment; coarse items
// that each run alone (a whole plan per command) pass 1, else up to 64 of them make one chunk and
// run on one thread.
template <typename Body>
void parallel_for(std::ptrdiff_t n, std::ptrdiff_t min_per_thread, Body&& body,
                  std::ptrdiff_t alignment = kChunkAlignment) {
  if (n <= 0) return;
  const std::ptrdiff_t min_chunk = std::max<std::ptrdiff_t>(1, min_per_thread);
  const std::ptrdiff_t threads =
      std::max<std::ptrdiff_t>(1, std::min<std::ptrdiff_t>(get_num_threads(), n / min_chunk));
  const InterruptPoll poll = interrupt_poll().load();
  const std::ptrdiff_t longest = detail::align_up(kMaxChunksPerGrain * min_chunk, alignment);
  if (threads <= 1 && (poll == nullptr || n <= longest)) {
    body(std::ptrdiff_t{0}, n);
    return;
  }
  // Chunks are handed out from a shared counter, about 8 per thread, so a core
  // that runs faster (cores of a VM often differ) takes more of the batch
  // instead of waiting for the slowest; each chunk starts on a block boundary.
  const std::ptrdiff_t grain =
      threads <= 1
          ? longest
          : std::min(longest,
                     detail::align_up(std::max<std::ptrdiff_t>(min_chunk / 4, n / (8 * threads)),
                                      alignment));
  std::atomic<std::ptrdiff_t> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;  // the first exception a worker threw
  std::atomic<bool> failed{false};
  auto run_chunks = [&](bool polling) {
    auto last_poll = std::chrono::steady_clock::now();
    while (!stop.load(std::memory_order_relaxed)) {
      const std::ptrdiff_t begin = next.fetch_add(grain, std::memory_order_relaxed);
      if (begin >= n) return;
      body(begin, std::min(n, begin + grain));
      if (polling) {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_poll >= kPollInterval) {
          last_poll = now;
          if (poll()) stop.store(true);
        }
      }
    }
  };
  auto worker = [&] {
    try {
      run_chunks(false);
    } catch (...) {
      if (!failed.exchange(true)) failure = std::current_exception();
      stop.store(true);
    }
  };
  // Starting a thread can fail (resource limits): the threads already started
  // and the calling thread share the whole batch, so fewer threads still finish it.
  std::vector<std::thread> workers;
  try {
    workers.reserve(static_cast<std::size_t>(threads - 1));
    for (std::ptrdiff_t t = 1; t < threads; ++t) workers.emplace_back(worker);
  } catch (const std::exception&) {
  }
  std::exception_ptr caller_failure;
  try {
    run_chunks(poll != nullptr);
  } catch (...) {
    caller_failure = std::current_exception();
    stop.store(true);
  }
  for (auto& w : workers) w.join();
  if (caller_failure) std::rethrow_exception(caller_failure);
  if (failure) std::rethrow_exception(failure);
  if (stop.load()) throw Interrupted();  // only the poll sets it without a failure
}

}  // namespace spotkin

// Output buffers for large batches.
//
// Fresh memory costs a page fault per page on first touch (about 2 us per 4 KiB
// page on the machines we measured, far more than the kernels' work per
// sample). Outputs of at least kMinBytes (1 MiB) are therefore mmap'd with
// MADV_HUGEPAGE, and when the NumPy array that owns one dies, the buffer goes
// to a small cache for the next call of a similar size. The cache is bounded
// (kMaxBuffers buffers, kMaxBytes in all; the count allows the chunks a pool of
// worker threads releases together); SPOTKIN_BUFFER_CACHE=0 disables it.
// Buffers are not zeroed: every kernel writes every output element.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <new>
#include <vector>

namespace spotkin::bindings {

class BufferCache {
 public:
  static constexpr std::size_t kMinBytes = std::size_t(1) << 20;
  static constexpr std::size_t kMaxBuffers = 32;
  static constexpr std::size_t kMaxBytes = std::size_t(1) << 30;

  static BufferCache& instance() {
    static auto* cache = new BufferCache();  // never destroyed: capsules may outlive statics
    return *cache;
  }

  bool enabled() const noexcept { return enabled_; }

  // A buffer of at least `bytes`, its true size in `capacity`.
  void* take(std::size_t bytes, std::size_t& capacity) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      std::size_t best = free_.size();
      for (std::size_t i = 0; i < free_.size(); ++i)
        if (free_[i].bytes >= bytes && free_[i].bytes <= 2 * bytes &&
            (best == free_.size() || free_[i].bytes < free_[best].bytes))
          best = i;
      if (best != free_.size()) {
        Block block = free_[best];
        free_.erase(free_.begin() + static_cast<std::ptrdiff_t>(best));
        cached_bytes_ -= block.bytes;
        capacity = block.bytes;
        return block.data;
      }
    }
    capacity = round_up(bytes);
    void* data = mmap(nullptr, capacity, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (data == MAP_FAILED) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(data, capacity, MADV_HUGEPAGE);
#endif
    return data;
  }

  void give(void* data, std::size_t bytes) noexcept {
    std::vector<Block> evicted;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back({data, bytes});
      cached_bytes_ += bytes;
      while (free_.size() > kMaxBuffers || cached_bytes_ > kMaxBytes) {  // oldest first
        evicted.push_back(free_.front());
        cached_bytes_ -= free_.front().bytes;
        free_.erase(free_.begin());
      }
    }
    for (const Block& block : evicted) munmap(block.data, block.bytes);
  }

 private:
  struct Block {
    void* data;
    std::size_t bytes;
  };

  BufferCache() {
    const char* env = std::getenv("SPOTKIN_BUFFER_CACHE");
    enabled_ = !(env && env[0] == '0');
  }

  static std::size_t round_up(std::size_t bytes) noexcept {
    constexpr std::size_t huge = std::size_t(2) << 20;
    return (bytes + huge - 1) / huge * huge;
  }

  std::mutex mutex_;
  std::vector<Block> free_;
  std::size_t cached_bytes_ = 0;
  bool enabled_ = true;
};

// A C-contiguous array of `shape`, backed by the cache when it is large.
template <typename T>
pybind11::array_t<T> cached_array(const std::vector<pybind11::ssize_t>& shape) {
  std::size_t bytes = sizeof(T);
  for (auto d : shape) bytes *= static_cast<std::size_t>(d);
  BufferCache& cache = BufferCache::instance();
  if (bytes < BufferCache::kMinBytes || !cache.enabled()) return pybind11::array_t<T>(shape);
  struct Owner {
    void* data;
    std::size_t capacity;
  };
  auto owned = std::make_unique<Owner>(Owner{nullptr, 0});
  owned->data = cache.take(bytes, owned->capacity);  // std::bad_alloc (MemoryError) when the OS refuses
  auto* owner = owned.release();
  pybind11::capsule base(owner, [](void* p) {
    auto* o = static_cast<Owner*>(p);
    BufferCache::instance().give(o->data, o->capacity);
    delete o;
  });
  return pybind11::array_t<T>(shape, static_cast<T*>(owner->data), base);
}

}  // namespace spotkin::bindings

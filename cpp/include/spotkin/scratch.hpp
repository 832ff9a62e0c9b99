// Work arrays for the batch kernels without a heap allocation per call: each thread
// keeps a stack of aligned memory that grows to the largest call it has served and is
// reused after that. A kernel's arrays are taken in scope order and given back when
// they go out of scope (last taken, first given back), so nested kernels share it.
// A single sample's call then costs no malloc: for the dynamics, the arrays of one
// 4-lane block are a few kilobytes, past the allocator's per-thread caches.
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <vector>

namespace spotkin {

class ScratchStack {
 public:
  struct Mark {
    std::size_t chunk, offset;
  };
  static ScratchStack& local() {
    thread_local ScratchStack stack;
    return stack;
  }
  Mark mark() const noexcept { return {chunk_, offset_}; }
  void release(Mark m) noexcept { chunk_ = m.chunk, offset_ = m.offset; }
  // `bytes` of memory aligned to `align` (at most kAlign), valid until released.
  void* take(std::size_t bytes, std::size_t align) {
    for (;;) {
      if (chunk_ < chunks_.size()) {
        const std::size_t start = (offset_ + align - 1) / align * align;
        if (start + bytes <= chunks_[chunk_].size) {
          offset_ = start + bytes;
          return chunks_[chunk_].data.get() + start;
        }
        if (chunk_ + 1 < chunks_.size() && bytes <= chunks_[chunk_ + 1].size) {
          ++chunk_, offset_ = 0;
          continue;
        }
      }
      // A new chunk after the current one (later, smaller chunks are dropped: they did not fit).
      const std::size_t grown = chunk_ < chunks_.size() ? 2 * chunks_[chunk_].size : 0;
      const std::size_t size = std::max<std::size_t>({bytes, kMinChunk, grown});
      chunks_.resize(chunks_.empty() ? 0 : std::min(chunks_.size(), chunk_ + 1));
      chunks_.push_back(Chunk{size, std::unique_ptr<std::byte[], Free>(static_cast<std::byte*>(
                                        ::operator new(size, std::align_val_t(kAlign))))});
      chunk_ = chunks_.size() - 1, offset_ = 0;
    }
  }
  static constexpr std::size_t kAlign = 64;

 private:
  struct Free {
    void operator()(std::byte* p) const noexcept { ::operator delete(p, std::align_val_t(kAlign)); }
  };
  struct Chunk {
    std::size_t size;
    std::unique_ptr<std::byte[], Free> data;
  };
  static constexpr std::size_t kMinChunk = 64 * 1024;
  std::vector<Chunk> chunks_;
  std::size_t chunk_ = 0, offset_ = 0;
};

// The tag of a ScratchArray whose elements are default-initialised: left as they are for packs and
// structs of packs (for an array the kernel writes in full before reading it: no memset).
struct Uninitialized {};
inline constexpr Uninitialized uninitialized{};
// The tag of a ScratchArray value-initialised (zeroed) or left as it is, by a flag.
struct ZeroIf {
  bool zero;
};

// n objects of type T (value-initialised, copies of `value`, or default-initialised) from the
// thread's ScratchStack, with the part of std::vector's interface the kernels use.
template <typename T>
class ScratchArray {
  static_assert(alignof(T) <= ScratchStack::kAlign, "ScratchArray aligns to at most 64 bytes");

 public:
  explicit ScratchArray(std::size_t n) : ScratchArray(ScratchStack::local(), n, nullptr) {}
  ScratchArray(std::size_t n, const T& value) : ScratchArray(ScratchStack::local(), n, &value) {}
  ScratchArray(std::size_t n, Uninitialized)
      : ScratchArray(ScratchStack::local(), n, nullptr, false) {}
  // The same from a stack the caller looked up once (ScratchStack::local()).
  ScratchArray(ScratchStack& stack, std::size_t n) : ScratchArray(stack, n, nullptr) {}
  ScratchArray(ScratchStack& stack, std::size_t n, const T& value)
      : ScratchArray(stack, n, &value) {}
  ScratchArray(ScratchStack& stack, std::size_t n, Uninitialized)
      : ScratchArray(stack, n, nullptr, false) {}
  ScratchArray(ScratchStack& stack, std::size_t n, ZeroIf zero)
      : ScratchArray(stack, n, nullptr, zero.zero) {}
  ScratchArray(const ScratchArray&) = delete;
  ScratchArray& operator=(const ScratchArray&) = delete;
  ~ScratchArray() {
    for (std::size_t i = n_; i-- > 0;) data_[i].~T();
    stack_.release(mark_);
  }
  T* data() noexcept { return data_; }
  const T* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return n_; }
  T& operator[](std::size_t i) noexcept { return data_[i]; }
  const T& operator[](std::size_t i) const noexcept { return data_[i]; }
  T* begin() noexcept { return data_; }
  T* end() noexcept { return data_ + n_; }

 private:
  ScratchArray(ScratchStack& stack, std::size_t n, const T* value, bool initialise = true)
      : stack_(stack),
        mark_(stack_.mark()),
        n_(n),
        data_(static_cast<T*>(stack_.take(n * sizeof(T) + (n == 0), alignof(T)))) {
    for (std::size_t i = 0; i < n; ++i) {
      if (value)
        new (data_ + i) T(*value);
      else if (initialise)
        new (data_ + i) T();
      else
        new (data_ + i) T;
    }
  }
  ScratchStack& stack_;
  ScratchStack::Mark mark_;
  std::size_t n_;
  T* data_;
};

}  // namespace spotkin

// Non-temporal (streaming) stores for large batch outputs: written once, never read back by the
// kernel, they skip the read for ownership of each cache line and do not evict the inputs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "spotkin/common.hpp"

namespace spotkin {

// Outputs of at least this many bytes per call are written with non-temporal
// stores (no read for ownership, no eviction of the inputs): a batch's output
// (2.6 kB per sample for an 18 x 18 mass matrix) is memory-bandwidth bound.
constexpr std::size_t kStreamBytes = std::size_t(2) << 20;

#if defined(__x86_64__)
// One non-temporal store of `bytes` bytes from `from` to the aligned `to`. The wide ones carry their
// instruction set (inlined into the clones of that level); stream_copy calls them only where
// stream_width_ok says the level runs.
template <int bytes>
struct StreamStore;
template <>
struct StreamStore<16> {
  static SPOTKIN_INLINE void put(void* to, const void* from) noexcept {
    _mm_stream_pd(static_cast<double*>(to), _mm_loadu_pd(static_cast<const double*>(from)));
  }
};
template <>
struct StreamStore<32> {
  __attribute__((target("avx"))) static inline void put(void* to, const void* from) noexcept {
    _mm256_stream_pd(static_cast<double*>(to), _mm256_loadu_pd(static_cast<const double*>(from)));
  }
};
template <>
struct StreamStore<64> {
  __attribute__((target("avx512f"))) static inline void put(void* to, const void* from) noexcept {
    _mm512_stream_pd(static_cast<double*>(to), _mm512_loadu_pd(static_cast<const double*>(from)));
  }
};
#endif

#if defined(__x86_64__)
// Whether the stores `bytes` wide may run: in the clone builds, the level that runs packs of that
// width (with_model), checked at run time too (a harness may run a wide model in a lower clone);
// elsewhere, what the compiler was told the CPU has.
template <int bytes>
SPOTKIN_INLINE bool stream_width_ok() noexcept {
#if SPOTKIN_HAS_ISA_CLONES
  return bytes <= 16 || (bytes == 32 ? active_isa() >= Isa::Avx2 : active_isa() == Isa::Avx512);
#elif defined(__AVX512F__)
  return true;
#elif defined(__AVX__)
  return bytes <= 32;
#else
  return bytes <= 16;
#endif
}

// stream_copy with stores `bytes` wide once `to` is aligned to them.
template <int bytes, typename M>
SPOTKIN_INLINE void stream_copy_by(const M* from, M* to, std::size_t count) noexcept {
  auto one = [&](std::size_t k) SPOTKIN_LAMBDA_INLINE {
    if constexpr (sizeof(M) == 8) {
      long long bits;
      std::memcpy(&bits, from + k, 8);
      _mm_stream_si64(reinterpret_cast<long long*>(to + k), bits);
    } else {
      int bits;
      std::memcpy(&bits, from + k, 4);
      _mm_stream_si32(reinterpret_cast<int*>(to + k), bits);
    }
  };
  constexpr std::size_t kPer = bytes / sizeof(M);
  std::size_t k = 0;
  for (; k < count && (reinterpret_cast<std::uintptr_t>(to + k) % bytes) != 0; ++k) one(k);
  for (; k + kPer <= count; k += kPer) StreamStore<bytes>::put(to + k, from + k);
  for (; k < count; ++k) one(k);
}
#endif

// to[0, count) = from[0, count) with non-temporal stores, a pack of L values wide (the clone's
// register) where that width may run, else 16 bytes wide.
template <typename M, int L>
SPOTKIN_INLINE void stream_copy(const M* from, M* to, std::size_t count) noexcept {
#if defined(__x86_64__)
  constexpr int kBytes = int(sizeof(M)) * L;
  if constexpr (kBytes == 32 || kBytes == 64) {
    if (stream_width_ok<kBytes>()) return stream_copy_by<kBytes>(from, to, count);
  }
  stream_copy_by<16>(from, to, count);
#else
  std::memcpy(to, from, sizeof(M) * count);
#endif
}

// Orders the non-temporal stores before what follows (the caller's use of the output).
SPOTKIN_INLINE void stream_fence() noexcept {
#if defined(__x86_64__)
  _mm_sfence();
#endif
}

}  // namespace spotkin

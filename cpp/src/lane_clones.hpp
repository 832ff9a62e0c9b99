// SPOTKIN_LANE_CLONES: the dynamics kernels' clones, one per lane width
// (dynamics_kernels.cpp, dynamics_floating_kernels.cpp).
#pragma once

#include <cstddef>

#include "spotkin/isa.hpp"

// SPOTKIN_LANE_CLONES(name, (parameters), (arguments), body) defines template <T, L> `name`:
// a model of 64-byte packs runs the AVX-512 clone, of 32-byte packs the AVX2 one, and of
// 16-byte packs the baseline one. One clone per width. The clones have internal linkage, as
// they had in the binding units: called from this unit only, GCC is free to inline them into
// `name` (Go2's packed CRBA at AVX2 was 4-5 % slower with external clones).
#if SPOTKIN_HAS_ISA_CLONES
#define SPOTKIN_LANE_CLONES(NAME, PARAMS, ARGS, ...)               \
  namespace {                                                       \
  template <typename T, int L>                                      \
  SPOTKIN_TARGET_AVX512 void NAME##_avx512 PARAMS { __VA_ARGS__ }   \
  template <typename T, int L>                                      \
  SPOTKIN_TARGET_AVX2 void NAME##_avx2 PARAMS { __VA_ARGS__ }       \
  template <typename T, int L>                                      \
  void NAME##_baseline PARAMS { __VA_ARGS__ }                       \
  }                                                                 \
  template <typename T, int L>                                      \
  void NAME PARAMS {                                              \
    constexpr std::size_t kBytes = sizeof(T) * L;                 \
    if constexpr (kBytes == 64) {                                 \
      NAME##_avx512 ARGS;                                         \
    } else if constexpr (kBytes == 32) {                          \
      NAME##_avx2 ARGS;                                           \
    } else {                                                      \
      NAME##_baseline ARGS;                                       \
    }                                                             \
  }
#else
#define SPOTKIN_LANE_CLONES(NAME, PARAMS, ARGS, ...) \
  template <typename T, int L>                       \
  void NAME PARAMS { __VA_ARGS__ }
#endif

// INSTANTIATE(T, L) for the six lane models: each precision at the three widths
// (spotkin/dynamics/kernels.hpp).
#define SPOTKIN_FOR_EACH_LANE_MODEL(INSTANTIATE) \
  INSTANTIATE(double, kLanes64)                  \
  INSTANTIATE(double, kMidLanes64)               \
  INSTANTIATE(double, kSmallLanes64)             \
  INSTANTIATE(float, kLanes32)                   \
  INSTANTIATE(float, kMidLanes32)                \
  INSTANTIATE(float, kSmallLanes32)

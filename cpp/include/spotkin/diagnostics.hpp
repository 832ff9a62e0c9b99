// Where the time goes: the TSC rate, the measured cost of the elementary
// vectorised operations the kernels are made of, and each kernel's operation
// counts, whose product is a floor estimate (memory traffic, selects, branch and
// limit logic are left out, so the floor is low). Shared by the C++ harness
// (bench/cpp) and the benchmark report (bench/, via spotkin._core).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

#if defined(__x86_64__)
#include <x86intrin.h>
#endif

namespace spotkin::diagnostics {

// What a kernel must evaluate per sample, at least.
struct Work {
  double atan2 = 0, sincos = 0, sqrt = 0, fma = 0;
};

// Operation counts per sample, from the kernels' equations (leg.hpp (I1)-(I4)
// and (R1), body.hpp (B1)-(B2), chain.hpp): a leg IK slot is one sqrt for the
// hip, one sqrt + one atan2 for the knee's acos, one atan2 each for hip roll
// and hip pitch, and about 40 multiply-adds; every slot (ik_all) shares the hip
// sqrt and, for a_z = 0, the knee.
struct KernelWork {
  const char* name;
  Work work;
};
constexpr KernelWork kKernels[] = {
    {"leg.fk", {0, 3, 0, 20}},
    {"leg.ik", {3, 0, 2, 40}},
    {"leg.ik_all", {7, 0, 2, 110}},
    {"body_ik", {12, 3, 8, 4 * 40 + 60}},
    {"body_fk", {0, 15, 0, 4 * 20 + 60}},
    {"chain6.fk", {0, 6, 0, 6 * 27}},
    {"chain6.jacobian", {0, 6, 0, 6 * 27 + 6 * 15}},
};

constexpr Work work_of(const char* name) noexcept {
  for (const KernelWork& k : kKernels) {
    const char *a = k.name, *b = name;
    while (*a && *a == *b) ++a, ++b;
    if (*a == *b) return k.work;
  }
  return Work{};
}

// ns per element of each elementary operation, measured.
struct Costs {
  double atan2 = 0, sincos = 0, sqrt = 0, fma = 0;
  double floor_ns(const Work& w) const noexcept {
    return w.atan2 * atan2 + w.sincos * sincos + w.sqrt * sqrt + w.fma * fma;
  }
};

// The elementary loops, vectorised as in the kernels (the caller compiles them
// per CPU level).
template <typename T>
SPOTKIN_INLINE void atan2_loop(const T* y, const T* x, T* out, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) out[i] = vector_math::atan2(y[i], x[i]);
}
template <typename T>
SPOTKIN_INLINE void sincos_loop(const T* x, T* s, T* c, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) vector_math::sincos_bounded(x[i], s[i], c[i]);
}
template <typename T>
SPOTKIN_INLINE void sqrt_loop(const T* x, T* out, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) out[i] = std::sqrt(x[i]);
}
// 32 dependent multiply-adds per element, over independent elements (throughput)
template <typename T>
SPOTKIN_INLINE void fma32_loop(const T* x, T* out, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    T v = x[i];
#pragma GCC unroll 32
    for (int k = 0; k < 32; ++k) v = v * T(0.999) + T(0.001);
    out[i] = v;
  }
}

// The TSC's rate in GHz, against steady_clock over `milliseconds`; 0 off x86-64.
inline double tsc_ghz(int milliseconds = 200) {
#if defined(__x86_64__)
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t c0 = __rdtsc();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(milliseconds)) {
  }
  const std::uint64_t c1 = __rdtsc();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return double(c1 - c0) / seconds * 1e-9;
#else
  (void)milliseconds;
  return 0.0;
#endif
}

template <class F>
double best_seconds(int repeats, F&& run) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

// Costs in T, best of `repeats` over 2^16 elements in cache. Loops: a type
// with static member functions atan2, sincos, sqrt, fma32 over T arrays (the
// caller's run-time dispatched instances of the loops above).
template <typename T, typename Loops>
Costs measure_costs(int repeats) {
  const std::ptrdiff_t m = 1 << 16;
  std::vector<T> a(m), b(m), c(m), d(m);
  std::mt19937_64 gen(1);
  std::uniform_real_distribution<double> uniform(-3, 3);
  for (std::ptrdiff_t i = 0; i < m; ++i) a[i] = T(uniform(gen)), b[i] = T(uniform(gen));
  const double per = 1e9 / double(m);
  Costs costs;
  costs.atan2 = best_seconds(repeats, [&] { Loops::atan2(a.data(), b.data(), c.data(), m); }) * per;
  costs.sincos = best_seconds(repeats, [&] { Loops::sincos(a.data(), c.data(), d.data(), m); }) * per;
  costs.sqrt = best_seconds(repeats, [&] { Loops::sqrt(b.data(), c.data(), m); }) * per;  // NaN half: same cost
  costs.fma = best_seconds(repeats, [&] { Loops::fma32(a.data(), c.data(), m); }) * per / 32.0;
  return costs;
}

}  // namespace spotkin::diagnostics

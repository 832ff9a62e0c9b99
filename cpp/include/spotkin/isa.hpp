// Instruction-set levels, and the run-time choice among a kernel's clones.
//
// On x86-64 (GCC), a kernel declared with SPOTKIN_CLONES is compiled three
// times: for baseline x86-64 (SSE2), x86-64-v3 (AVX2 + FMA) and x86-64-v4
// (AVX-512). Each call runs the clone of the active level: the best one the CPU
// has, unless SPOTKIN_ISA or set_isa() forces a lower one (for benchmarking
// and testing every level on one machine). Elsewhere (aarch64, Clang, a
// -DSPOTKIN_NATIVE=ON build) there is one version, compiled for the target.
//
// Each clone's body sees `kIsa`, its level, as a constant expression, so that
// lane widths can follow the level.
#pragma once

#include <atomic>
#include <cstdlib>
#include <stdexcept>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SPOTKIN_NATIVE_BUILD)
#define SPOTKIN_HAS_ISA_CLONES 1
#else
#define SPOTKIN_HAS_ISA_CLONES 0
#endif

namespace spotkin {

// Baseline is SSE2 on x86-64, the target's own baseline elsewhere (NEON on aarch64).
enum class Isa : int { Baseline = 0, Avx2 = 1, Avx512 = 2 };

// The bytes of one vector register at a level (SSE2 and NEON: 16).
constexpr int register_bytes(Isa isa) noexcept {
  return isa == Isa::Avx512 ? 64 : isa == Isa::Avx2 ? 32 : 16;
}

// The levels' names, as SPOTKIN_ISA and spotkin.set_isa take them.
inline const char* isa_name(Isa isa) noexcept {
#if SPOTKIN_HAS_ISA_CLONES
  switch (isa) {
    case Isa::Avx512: return "avx512";
    case Isa::Avx2: return "avx2";
    default: return "sse2";
  }
#elif defined(__aarch64__)
  (void)isa;
  return "neon";
#else
  (void)isa;
  return "native";
#endif
}

// The best level this CPU runs, among the compiled ones.
inline Isa best_isa() noexcept {
#if SPOTKIN_HAS_ISA_CLONES
  static const Isa best = [] {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("x86-64-v4")) return Isa::Avx512;
    if (__builtin_cpu_supports("x86-64-v3")) return Isa::Avx2;
    return Isa::Baseline;
  }();
  return best;
#else
  return Isa::Baseline;
#endif
}

namespace detail {
inline std::atomic<int>& isa_setting() noexcept {
  static std::atomic<int> setting{-1};  // -1: not chosen yet (the best level)
  return setting;
}
}  // namespace detail

// The level whose clones run now.
inline Isa active_isa() noexcept {
  const int setting = detail::isa_setting().load(std::memory_order_relaxed);
  return setting < 0 ? best_isa() : static_cast<Isa>(setting);
}

// The level named `name` ("sse2", "avx2", "avx512"; "best" for the best the CPU
// has). std::invalid_argument for an unknown name or a level the CPU lacks.
inline Isa isa_from_name(const std::string& name) {
  if (name == "best") return best_isa();
  for (int level = static_cast<int>(best_isa()); level >= 0; --level) {
    if (name == isa_name(static_cast<Isa>(level))) return static_cast<Isa>(level);
  }
  std::string known;
#if SPOTKIN_HAS_ISA_CLONES
  for (const char* level : {"sse2", "avx2", "avx512"}) {
#else
  for (const char* level : {isa_name(Isa::Baseline)}) {
#endif
    if (name == level)
      throw std::invalid_argument("this CPU lacks " + name + " (its best level is " +
                                  isa_name(best_isa()) + ")");
    known += std::string(known.empty() ? "" : ", ") + level;
  }
  throw std::invalid_argument("unknown instruction-set level '" + name + "': one of " + known +
                              " (those the CPU has), or best");
}

// Makes calls started from now on run the clones of `isa` (a level the CPU has).
inline void set_isa(Isa isa) {
  if (static_cast<int>(isa) < 0 || static_cast<int>(isa) > static_cast<int>(best_isa()))
    throw std::invalid_argument(std::string("this CPU lacks ") + isa_name(isa));
  detail::isa_setting().store(static_cast<int>(isa), std::memory_order_relaxed);
}

// The level SPOTKIN_ISA asks for (the best one when unset or empty).
inline Isa isa_from_environment() {
  const char* text = std::getenv("SPOTKIN_ISA");
  if (text == nullptr || *text == '\0') return best_isa();
  try {
    return isa_from_name(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("SPOTKIN_ISA=") + text + ": " + e.what());
  }
}

}  // namespace spotkin

#define SPOTKIN_ISA_ID(...) __VA_ARGS__

// SPOTKIN_CLONES((attributes), return type, name, (parameters), (arguments), body)
// defines `name` and its clones name_avx512, name_avx2, name_baseline; `name`
// calls the clone of the active level. The body sees `kIsa`. SPOTKIN_CLONES_T
// takes explicit template arguments for the calls, such as (<Format>), for
// template parameters the arguments do not deduce.
#if SPOTKIN_HAS_ISA_CLONES
#define SPOTKIN_TARGET_AVX512 __attribute__((target("arch=x86-64-v4")))
#define SPOTKIN_TARGET_AVX2 __attribute__((target("arch=x86-64-v3")))
#define SPOTKIN_CLONES_T(ATTRS, RET, NAME, TARGS, PARAMS, ARGS, ...)                \
  SPOTKIN_ISA_ID ATTRS SPOTKIN_TARGET_AVX512 RET NAME##_avx512 PARAMS {             \
    [[maybe_unused]] constexpr ::spotkin::Isa kIsa = ::spotkin::Isa::Avx512;        \
    __VA_ARGS__                                                                     \
  }                                                                                 \
  SPOTKIN_ISA_ID ATTRS SPOTKIN_TARGET_AVX2 RET NAME##_avx2 PARAMS {                 \
    [[maybe_unused]] constexpr ::spotkin::Isa kIsa = ::spotkin::Isa::Avx2;          \
    __VA_ARGS__                                                                     \
  }                                                                                 \
  SPOTKIN_ISA_ID ATTRS RET NAME##_baseline PARAMS {                                 \
    [[maybe_unused]] constexpr ::spotkin::Isa kIsa = ::spotkin::Isa::Baseline;      \
    __VA_ARGS__                                                                     \
  }                                                                                 \
  SPOTKIN_ISA_ID ATTRS RET NAME PARAMS {                                            \
    switch (::spotkin::active_isa()) {                                              \
      case ::spotkin::Isa::Avx512: return NAME##_avx512 SPOTKIN_ISA_ID TARGS ARGS;  \
      case ::spotkin::Isa::Avx2: return NAME##_avx2 SPOTKIN_ISA_ID TARGS ARGS;      \
      default: return NAME##_baseline SPOTKIN_ISA_ID TARGS ARGS;                    \
    }                                                                               \
  }
#else
#define SPOTKIN_CLONES_T(ATTRS, RET, NAME, TARGS, PARAMS, ARGS, ...)           \
  SPOTKIN_ISA_ID ATTRS RET NAME PARAMS {                                       \
    [[maybe_unused]] constexpr ::spotkin::Isa kIsa = ::spotkin::Isa::Baseline; \
    __VA_ARGS__                                                                \
  }
#endif
#define SPOTKIN_CLONES(ATTRS, RET, NAME, PARAMS, ARGS, ...) \
  SPOTKIN_CLONES_T(ATTRS, RET, NAME, (), PARAMS, ARGS, __VA_ARGS__)

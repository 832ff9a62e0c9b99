// Run-time CPU dispatch for batch kernels. A function marked SPOTKIN_MULTIVERSION
// is compiled three times, for baseline x86-64, x86-64-v3 (AVX2 + FMA) and
// x86-64-v4 (AVX-512); the
// loader picks the best one for the running CPU, so one wheel runs everywhere.
// The core's per-sample code is force-inlined into each clone. A native build
// (-DSPOTKIN_NATIVE=ON) compiles one version for the build machine instead.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SPOTKIN_NATIVE_BUILD)
#define SPOTKIN_MULTIVERSION __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define SPOTKIN_MULTIVERSION
#endif

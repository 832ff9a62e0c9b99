// Run-time CPU dispatch for batch kernels: a kernel defined with SPOTKIN_CLONES
// (spotkin/isa.hpp) is compiled for baseline x86-64, x86-64-v3 (AVX2 + FMA) and
// x86-64-v4 (AVX-512), and each call runs the clone of the active level (the
// best the CPU has, or the one SPOTKIN_ISA or spotkin.set_isa chose), so one
// wheel runs everywhere. The core's per-sample code is force-inlined into each
// clone. A native build (-DSPOTKIN_NATIVE=ON) compiles one version for the build
// machine instead.
#pragma once

#include "spotkin/isa.hpp"

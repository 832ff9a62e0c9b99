// The dynamics' batch kernels over lane models (spotkin/dynamics/batch.hpp and
// floating.hpp), compiled in cpp/src/dynamics_kernels.cpp, apart from the bindings.
// Each is instantiated for the three lane widths of each precision; a model whose packs
// fill 64 bytes runs the AVX-512 clone, 32 bytes the AVX2 one and 16 bytes the baseline
// one (SSE2, NEON), and the bindings pick the model of the active level (with_model in
// cpp/bindings/dynamics_boundary.hpp). Rows [b, e) of the batch are computed; `stream` stores
// them with non-temporal stores (spotkin/stream.hpp), which the caller decides from the whole
// call's output, not from [b, e).
#pragma once

#include <cstddef>

#include "spotkin/dynamics/floating.hpp"
#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

// Lane widths: one register of the level (AVX-512: 8 doubles, 16 floats; AVX2: 4, 8),
// and 16-byte packs (2, 4) for SSE2 and NEON.
constexpr int kLanes64 = 8;
constexpr int kLanes32 = 16;
constexpr int kMidLanes64 = 4;
constexpr int kMidLanes32 = 8;
constexpr int kSmallLanes64 = 2;
constexpr int kSmallLanes32 = 4;

// A parameter type left out of template argument deduction (std::type_identity_t in C++20):
// the kernels deduce T and L from the model alone, so nullptr passes for an absent input.
template <typename X>
struct NonDeducedOf {
  using type = X;
};
template <typename X>
using NonDeduced = typename NonDeducedOf<X>::type;

// Fixed base (ChainModel). qd, qdd null: zero.
template <typename T, int L>
void rnea_k(const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, const NonDeduced<Rows<T>>* qd,
            const NonDeduced<Rows<T>>* qdd, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream);
template <typename T, int L>
void crba_k(const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream,
            SymmetricLayout layout);
template <typename T, int L>
void coriolis_k(const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, T* out, std::ptrdiff_t b,
                std::ptrdiff_t e, bool stream);
template <typename T, int L>
void aba_k(const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, NonDeduced<Rows<T>> tau,
           NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream);

// Floating base (FloatingModel). v, a null: zero.
template <typename T, int L>
void floating_rnea_k(const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, const NonDeduced<Rows<T>>* v,
                     const NonDeduced<Rows<T>>* a, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream);
template <typename T, int L>
void floating_crba_k(const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream,
                     SymmetricLayout layout);
template <typename T, int L>
void floating_aba_k(const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> v,
                    NonDeduced<Rows<T>> tau, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream);
template <typename T, int L>
void floating_coriolis_k(const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> v, T* out,
                         std::ptrdiff_t b, std::ptrdiff_t e, bool stream);
// The centre of mass (n, 3), or with `jacobian` its Jacobian (n, 3, nv).
template <typename T, int L>
void floating_com_k(const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, bool jacobian, std::ptrdiff_t b,
                    std::ptrdiff_t e, bool stream);

}  // namespace spotkin::dynamics

// Dynamic-size Eigen matrices with a kMaxDim cap (stack storage), shared by the
// decompositions in differential.cpp and singular_values.cpp. The decompositions
// run in double for float32 input too (copied in, rounded out; the cutoffs stay
// float32's): one instantiation of each Eigen decomposition, not two, for a
// build that is 40 % shorter there, and float32 results at least as accurate.
#pragma once

#include <Eigen/Core>

#include "spotkin/differential.hpp"

namespace spotkin::differential {

constexpr int Dyn = Eigen::Dynamic;

template <typename S>
struct Types {
  using Jac = Eigen::Matrix<S, Dyn, Dyn, Eigen::RowMajor, kMaxDim, kMaxDim>;  // row-major like numpy
  using JacT = Jac;
  using SquareM = Eigen::Matrix<S, Dyn, Dyn, Eigen::ColMajor, kMaxDim, kMaxDim>;
  using SquareN = Eigen::Matrix<S, Dyn, Dyn, Eigen::RowMajor, kMaxDim, kMaxDim>;
  using VecM = Eigen::Matrix<S, Dyn, 1, Eigen::ColMajor, kMaxDim, 1>;
  using VecN = VecM;
  using ColMajor = Eigen::Matrix<S, Dyn, Dyn, Eigen::ColMajor, kMaxDim, kMaxDim>;
};

template <typename S>
inline Eigen::Map<const typename Types<S>::Jac> map_jacobian(const S* J, int m, int n) noexcept {
  return Eigen::Map<const typename Types<S>::Jac>(J, m, n);
}

template <typename S>
using VecOf = Eigen::Matrix<S, Dyn, 1, Eigen::ColMajor, kMaxDim, 1>;
template <typename S>
using RowMajorOf = Eigen::Matrix<S, Dyn, Dyn, Eigen::RowMajor, kMaxDim, kMaxDim>;  // numpy's layout

// J (m x n) and x (k) as double matrices.
template <typename S>
inline Types<double>::Jac jacobian_in_double(const S* J, int m, int n) noexcept {
  return map_jacobian<S>(J, m, n).template cast<double>();
}
template <typename S>
inline Types<double>::VecM vector_in_double(const S* x, int k) noexcept {
  return Eigen::Map<const VecOf<S>>(x, k).template cast<double>();
}

}  // namespace spotkin::differential

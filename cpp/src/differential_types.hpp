// Dynamic-size Eigen matrices with a kMaxDim cap (stack storage), shared by the
// decompositions in differential.cpp and singular_values.cpp.
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

}  // namespace spotkin::differential

// spotkin/dense.hpp: Eigen's decompositions, instantiated once for the whole build.
#include "spotkin/dense.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

namespace spotkin::dense {

double determinant6(const double* a_row_major) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(a_row_major).determinant();
}

Eigen::Vector3d svd_solve3(const Eigen::Matrix3d& A, const Eigen::Vector3d& b, Eigen::Vector3d* sigma) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (sigma) *sigma = svd.singularValues();
  return svd.solve(b);
}

Eigen::Vector3d singular_values3(const Eigen::Matrix3d& A) { return Eigen::JacobiSVD<Eigen::Matrix3d>(A).singularValues(); }

void svd_u2(const Eigen::Matrix2d& A, Eigen::Vector2d& sigma, Eigen::Matrix2d& U) {
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(A, Eigen::ComputeFullU);
  sigma = svd.singularValues();
  U = svd.matrixU();
}

Eigen::Matrix<double, 5, 5> inverse5(const Eigen::Matrix<double, 5, 5>& A) { return A.inverse(); }

void cod_solve6(const double* J_row_major, int n, const double* e, double threshold, double* dq) {
  using Mat = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor, 6, 7>;
  Eigen::CompleteOrthogonalDecomposition<Mat> cod(6, n);
  cod.setThreshold(threshold);
  cod.compute(Eigen::Map<const Mat>(J_row_major, 6, n));
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 7, 1> x = cod.solve(Eigen::Map<const Eigen::Matrix<double, 6, 1>>(e));
  for (int j = 0; j < n; ++j) dq[j] = x[j];
}

Eigen::Vector3d lstsq43(const Eigen::Matrix<double, 4, 3>& X, const Eigen::Vector4d& z) {
  return X.completeOrthogonalDecomposition().solve(z);
}

}  // namespace spotkin::dense

// spotkin/dense.hpp: Eigen's decompositions, instantiated once for the whole build.
#include "spotkin/dense.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

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

void thin_svd3(const double* A, int rows, double* U, double S[3], double* V) {
  // Householder QR: H_k = I - 2 v_k v_k^T / |v_k|^2 zeroes column k below the diagonal; v_k = x -
  // alpha e_k with alpha = -sign(x_k) |x|, so that x_k - alpha does not cancel. A zero column: no
  // reflection.
  double R[kMaxThinRows][3], v[3][kMaxThinRows], v_norm2[3];
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < 3; ++j) R[i][j] = A[3 * i + j];
  for (int k = 0; k < 3; ++k) {
    double x_norm2 = 0.0;
    for (int i = k; i < rows; ++i) x_norm2 += R[i][k] * R[i][k];
    const double x_norm = std::sqrt(x_norm2), alpha = R[k][k] >= 0.0 ? -x_norm : x_norm;
    for (int i = k; i < rows; ++i) v[k][i] = R[i][k];
    v[k][k] -= alpha;
    v_norm2[k] = 0.0;
    for (int i = k; i < rows; ++i) v_norm2[k] += v[k][i] * v[k][i];
    if (!(v_norm2[k] > 0.0)) continue;
    for (int j = k; j < 3; ++j) {
      double dot = 0.0;
      for (int i = k; i < rows; ++i) dot += v[k][i] * R[i][j];
      const double f = 2.0 * dot / v_norm2[k];
      for (int i = k; i < rows; ++i) R[i][j] -= f * v[k][i];
    }
  }
  Eigen::Matrix3d upper = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) upper(i, j) = R[i][j];
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(upper, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // U = H_0 H_1 H_2 [U_R; 0]
  double M[kMaxThinRows][3];
  for (int i = 0; i < rows; ++i)
    for (int c = 0; c < 3; ++c) M[i][c] = i < 3 ? svd.matrixU()(i, c) : 0.0;
  for (int k = 2; k >= 0; --k) {
    if (!(v_norm2[k] > 0.0)) continue;
    for (int c = 0; c < 3; ++c) {
      double dot = 0.0;
      for (int i = k; i < rows; ++i) dot += v[k][i] * M[i][c];
      const double f = 2.0 * dot / v_norm2[k];
      for (int i = k; i < rows; ++i) M[i][c] -= f * v[k][i];
    }
  }
  for (int i = 0; i < rows; ++i)
    for (int c = 0; c < 3; ++c) U[3 * i + c] = M[i][c];
  for (int a = 0; a < 3; ++a) {
    S[a] = svd.singularValues()(a);
    for (int c = 0; c < 3; ++c) V[3 * a + c] = svd.matrixV()(a, c);
  }
}

Eigen::Vector3d lstsq43(const Eigen::Matrix<double, 4, 3>& X, const Eigen::Vector4d& z) {
  double A[12], U[12], S[3], V[9];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) A[3 * i + j] = X(i, j);
  thin_svd3(A, 4, U, S, V);
  const double cutoff = 4.0 * std::numeric_limits<double>::epsilon() * S[0];
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) {
    if (!(S[a] > cutoff)) continue;
    double w = 0.0;  // (U^T z)_a / S_a
    for (int i = 0; i < 4; ++i) w += U[3 * i + a] * z(i);
    w /= S[a];
    for (int j = 0; j < 3; ++j) x(j) += V[3 * j + a] * w;
  }
  return x;
}

}  // namespace spotkin::dense

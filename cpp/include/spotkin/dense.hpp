// Small dense decompositions used off the vector paths (solver construction, a scalar
// polish, diagnostics), compiled once in cpp/src/dense.cpp: GCC spends seconds
// instantiating each of Eigen's decompositions, and a header definition made every unit
// that included it pay again (a unit pays even when it never calls the function).
#pragma once

#include <Eigen/Core>

namespace spotkin::dense {

// det(A) of a 6x6 row-major matrix (partial-pivot LU).
double determinant6(const double* a_row_major);
// Least-squares x = A^+ b by Eigen's JacobiSVD (full U and V, its default threshold), with the
// singular values of A (descending) in `sigma` when not null.
Eigen::Vector3d svd_solve3(const Eigen::Matrix3d& A, const Eigen::Vector3d& b, Eigen::Vector3d* sigma = nullptr);
// The singular values of A, descending.
Eigen::Vector3d singular_values3(const Eigen::Matrix3d& A);
// The singular values of A (descending) and the left singular vectors U.
void svd_u2(const Eigen::Matrix2d& A, Eigen::Vector2d& sigma, Eigen::Matrix2d& U);
// A^-1 of a 5x5 matrix (partial-pivot LU).
Eigen::Matrix<double, 5, 5> inverse5(const Eigen::Matrix<double, 5, 5>& A);
// dq = J^+ e for a 6 x n row-major J (n <= 7) by a complete orthogonal decomposition whose
// rank drops the singular directions below `threshold` times the largest (compiled in
// cpp/src/differential.cpp, with the decomposition's other use).
void cod_solve6(const double* J_row_major, int n, const double* e, double threshold, double* dq);
// The thin SVD A = U diag(S) V^T of a tall A (rows x 3, 3 <= rows <= kMaxThinRows, row-major), S
// descending: Householder QR, A = Q R, then R's 3 x 3 Jacobi SVD, R = U_R diag(S) V^T, and
// U = Q U_R (LAPACK's path for tall matrices). U is rows x 3, V 3 x 3, both row-major. (Eigen's
// JacobiSVD of a dynamic-size matrix cost 12 s of compiling for its QR preconditioners.)
constexpr int kMaxThinRows = 24;
void thin_svd3(const double* A_row_major, int rows, double* U_row_major, double S[3],
               double* V_row_major);
// The minimum-norm least-squares x of X x = z for a 4 x 3 X: V S^+ U^T z from thin_svd3, with the
// singular values up to 4 eps times the largest taken as zero (NumPy's lstsq default cutoff).
Eigen::Vector3d lstsq43(const Eigen::Matrix<double, 4, 3>& X, const Eigen::Vector4d& z);

}  // namespace spotkin::dense

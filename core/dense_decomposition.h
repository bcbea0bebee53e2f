#pragma once
// The one entry to the library's dense decompositions: QR (plain and column-pivoting), SVD, LLT and LDLT, LU, the
// complete orthogonal decomposition and the symmetric eigen-decomposition. Every one of them is built here, and a
// matrix holding a NaN or an infinity is refused with the name of what it was being asked ("the scoring of
// candidate thermal_drift", "the normal equations of parameter block pose"), the size and the first bad entry.
//
// Why one gate and not a check at each call: a pivoting decomposition given a NaN picks no pivot at all and Eigen
// then indexes out of bounds (fvm diagnose died with SIGSEGV on one gross outlier, issue 44; FindDependentColumns
// the round before); the others return garbage that the caller cannot tell from a result. One entry is one place
// to get right, and tests/core/dense_decomposition_sources_test.sh fails when a file outside this one constructs a
// decomposition directly.
//
// Use:  const auto qr = Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(a, "the base model's columns");
//       Decompose<Eigen::JacobiSVD<Eigen::Matrix3d>>(h, "the rotation fit", Eigen::ComputeFullU | Eigen::ComputeFullV);
// A rank-revealing decomposition whose threshold must be set before it is computed (the complete orthogonal
// decomposition builds Z for the rank found then): DecomposeWithThreshold<...>(a, 1e-2, "what").

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace fvm {

// A matrix with NaN or infinity handed to a decomposition: a number that is not finite reached the numerics, from
// the input or from a step before (an overflow, a division by zero). Callers map it to "bad input" (exit 1).
struct NonFiniteMatrix : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// "WHAT: the RxC matrix holds VALUE at row I, column J; ..." (rows and columns from 0).
[[noreturn]] void ThrowNonFiniteMatrix(std::string_view what, Eigen::Index rows, Eigen::Index cols, Eigen::Index row,
                                       Eigen::Index col, double value);

// Throws NonFiniteMatrix naming `what` unless every entry of `m` is finite.
template <class Derived>
void RequireFiniteMatrix(const Eigen::DenseBase<Derived>& m, std::string_view what) {
  if (m.allFinite()) return;
  const typename Derived::PlainObject plain = m;  // an expression is evaluated once to find the entry
  for (Eigen::Index j = 0; j < plain.cols(); ++j) {
    for (Eigen::Index i = 0; i < plain.rows(); ++i) {
      const double v = static_cast<double>(plain(i, j));
      if (!std::isfinite(v)) ThrowNonFiniteMatrix(what, plain.rows(), plain.cols(), i, j, v);
    }
  }
  ThrowNonFiniteMatrix(what, plain.rows(), plain.cols(), 0, 0, 0.0);  // unreachable: allFinite said otherwise
}

// The decomposition of `m` (any Eigen expression; a non-const Eigen::Ref for the in-place kinds), after the check.
// `options` go to the decomposition's constructor after the matrix (SVD's ComputeThinU, ...).
template <class Decomposition, class Matrix, class... Options>
Decomposition Decompose(Matrix&& m, std::string_view what, Options... options) {
  RequireFiniteMatrix(m, what);
  return Decomposition(m, options...);  // an lvalue: a non-const Eigen::Ref takes the in-place constructor
}

// The same with the rank threshold set before the decomposition is computed.
template <class Decomposition, class Matrix>
Decomposition DecomposeWithThreshold(const Matrix& m, double threshold, std::string_view what) {
  RequireFiniteMatrix(m, what);
  Decomposition d(m.rows(), m.cols());
  d.setThreshold(threshold);
  d.compute(m);
  return d;
}

}  // namespace fvm

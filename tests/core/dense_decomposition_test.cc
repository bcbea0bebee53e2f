// The guarded entry to the dense decompositions (issue 44): a matrix with NaN or infinity is refused naming what
// was asked and where the bad entry is; a finite one gives what Eigen gives.

#include "core/dense_decomposition.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace fvm {
namespace {

using ::testing::HasSubstr;

TEST(DenseDecomposition, RefusesNaNNamingWhatWasAskedAndWhere) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(4, 3);
  a(2, 1) = std::numeric_limits<double>::quiet_NaN();
  try {
    Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(a, "the scoring of candidate outliers");
    FAIL() << "a NaN was decomposed";
  } catch (const NonFiniteMatrix& e) {
    EXPECT_THAT(e.what(), HasSubstr("the scoring of candidate outliers: the 4x3 matrix"));
    EXPECT_THAT(e.what(), HasSubstr("nan at row 2, column 1"));
  }
}

TEST(DenseDecomposition, RefusesInfinityInAnExpressionAndEveryKind) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();
  h(0, 2) = -std::numeric_limits<double>::infinity();
  EXPECT_THROW(Decompose<Eigen::LDLT<Eigen::Matrix3d>>(h.transpose() * h, "ldlt"), NonFiniteMatrix);
  EXPECT_THROW(Decompose<Eigen::LLT<Eigen::Matrix3d>>(h, "llt"), NonFiniteMatrix);
  EXPECT_THROW(Decompose<Eigen::JacobiSVD<Eigen::Matrix3d>>(h, "svd", Eigen::ComputeFullU), NonFiniteMatrix);
  EXPECT_THROW(Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(h, "eigen"), NonFiniteMatrix);
  EXPECT_THROW(Decompose<Eigen::FullPivLU<Eigen::Matrix3d>>(h, "lu"), NonFiniteMatrix);
  EXPECT_THROW(
      (DecomposeWithThreshold<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(Eigen::MatrixXd(h), 1e-2, "cod")),
      NonFiniteMatrix);
  // Refused as bad input: std::invalid_argument, which fvm maps to exit 1.
  EXPECT_THROW(Decompose<Eigen::HouseholderQR<Eigen::Matrix3d>>(h, "qr"), std::invalid_argument);
}

TEST(DenseDecomposition, FiniteMatricesDecomposeAsEigenDoes) {
  Eigen::MatrixXd a(4, 2);
  a << 1, 0, 1, 1, 1, 2, 1, 3;
  const Eigen::VectorXd b = (Eigen::VectorXd(4) << 1, 3, 5, 7).finished();
  const Eigen::VectorXd x = Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(a, "line").solve(b);
  EXPECT_NEAR(x[0], 1.0, 1e-12);
  EXPECT_NEAR(x[1], 2.0, 1e-12);
  // In place on a Ref, as identification's QR of the large Jacobian.
  Eigen::MatrixXd j = a;
  const auto qr = Decompose<Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>>>(Eigen::Ref<Eigen::MatrixXd>(j), "in place");
  EXPECT_NEAR(std::abs(qr.matrixQR()(0, 0)), 2.0, 1e-12);  // |first column| = 2, written into j itself
  EXPECT_NEAR(std::abs(j(0, 0)), 2.0, 1e-12);
  // The threshold set before computing decides the rank.
  Eigen::MatrixXd flat(3, 2);
  flat << 1, 0, 0, 1e-3, 0, 0;
  EXPECT_EQ((DecomposeWithThreshold<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(flat, 1e-2, "flat").rank()), 1);
  EXPECT_EQ((DecomposeWithThreshold<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(flat, 1e-6, "flat").rank()), 2);
}

}  // namespace
}  // namespace fvm

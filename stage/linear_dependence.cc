#include "stage/linear_dependence.h"

#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

#include "core/dense_decomposition.h"

namespace fvm::stage {

std::vector<ColumnDependence> FindDependentColumns(const Eigen::MatrixXd& j, const std::vector<int>& order,
                                                   double relative_tolerance) {
  // Pivoting on NaN picks no column at all (Eigen then indexes out of bounds): refuse it before any work.
  RequireFiniteMatrix(j, "the search for dependent parameters (the Jacobian's columns)");
  std::vector<ColumnDependence> dependent;
  std::vector<int> kept;
  Eigen::MatrixXd basis(j.rows(), 0);  // orthonormal basis of the kept columns
  for (int c : order) {
    const Eigen::VectorXd column = j.col(c);
    const double norm = column.norm();
    if (norm == 0.0) {
      dependent.push_back({c, {}});
      continue;
    }
    // Gram-Schmidt twice ("twice is enough") keeps the basis orthonormal to rounding.
    Eigen::VectorXd rest = column;
    for (int pass = 0; pass < 2; ++pass) rest -= basis * (basis.transpose() * rest);
    if (rest.norm() > relative_tolerance * norm) {
      kept.push_back(c);
      basis.conservativeResize(Eigen::NoChange, basis.cols() + 1);
      basis.col(basis.cols() - 1) = rest / rest.norm();
      continue;
    }
    Eigen::MatrixXd kept_columns(j.rows(), static_cast<Eigen::Index>(kept.size()));
    for (size_t k = 0; k < kept.size(); ++k) kept_columns.col(static_cast<Eigen::Index>(k)) = j.col(kept[k]);
    const Eigen::VectorXd factors =
        Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(kept_columns, "the parameters column " + std::to_string(c) +
                                                               " depends on")
            .solve(column);
    ColumnDependence d{c, {}};
    for (size_t k = 0; k < kept.size(); ++k) {
      const double f = factors[static_cast<Eigen::Index>(k)];
      if (std::abs(f) * j.col(kept[k]).norm() > 1e-6 * norm) d.on.emplace_back(kept[k], f);
    }
    dependent.push_back(std::move(d));
  }
  return dependent;
}

}  // namespace fvm::stage

#pragma once
// Which columns of a Jacobian the earlier ones already explain: the core of alias detection.

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace fvm::stage {

struct ColumnDependence {
  int column = 0;
  std::vector<std::pair<int, double>> on;  // column = sum of factor * column over `on` (empty: a zero column)
};

// Walks the columns in `order`; a column whose residual after projection onto the kept columns is below
// `relative_tolerance` times its norm depends on them (factors by least squares); otherwise it is kept. A matrix
// holding inf or NaN is refused (std::invalid_argument).
std::vector<ColumnDependence> FindDependentColumns(const Eigen::MatrixXd& j, const std::vector<int>& order,
                                                   double relative_tolerance);

}  // namespace fvm::stage

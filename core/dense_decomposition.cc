#include "core/dense_decomposition.h"

#include <fmt/core.h>

namespace fvm {

void ThrowNonFiniteMatrix(std::string_view what, Eigen::Index rows, Eigen::Index cols, Eigen::Index row,
                          Eigen::Index col, double value) {
  throw NonFiniteMatrix(fmt::format(
      "{}: the {}x{} matrix to decompose holds {} at row {}, column {}; a number that is not finite came in with the "
      "data or was made from it (an overflow, a division by zero): check the input for nan, inf, empty cells and "
      "values far beyond their range",
      what, rows, cols, value, row, col));
}

}  // namespace fvm

// The conversions between numpy arrays and the libraries' point and vector types (python/bindings.h), with the
// shape and finiteness checks every function that takes points makes.

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <vector>

#include "core/input_error.h"
#include "python/bindings.h"

namespace fvm::python {

std::vector<Eigen::Vector3d> PointsFrom(const DoubleArray& array, const std::string& what, bool finite) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    const std::vector<py::ssize_t> shape(array.shape(), array.shape() + array.ndim());
    throw InputError(fmt::format("{}: expected an N x 3 array of x, y, z (mm), got shape ({})", what, fmt::join(shape, " x ")));
  }
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(array.shape(0)));
  const double* data = array.data();
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector3d(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    if (finite && !points[i].allFinite()) {
      throw InputError(fmt::format("{}: row {} is not finite ({}, {}, {}); remove invalid points first", what, i,
                                   points[i].x(), points[i].y(), points[i].z()));
    }
  }
  return points;
}

py::array_t<double> PointsArray(const std::vector<Eigen::Vector3d>& points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  double* data = out.mutable_data();
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) data[3 * i + static_cast<std::size_t>(k)] = points[i][k];
  }
  return out;
}

py::array_t<double> VectorArray(const Eigen::Vector3d& v) {
  py::array_t<double> out(3);
  for (int k = 0; k < 3; ++k) out.mutable_at(k) = v[k];
  return out;
}

}  // namespace fvm::python

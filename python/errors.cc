// Errors as Python exceptions carrying the command line's messages: fvm.InputError (a ValueError: a file, value or
// combination to fix, exit 1 of the CLI) and fvm.NotConvergedError (a RuntimeError: the solver did not converge,
// exit 3).

#include <pybind11/stl.h>

#include <exception>
#include <stdexcept>
#include <fmt/core.h>

#include "core/exit_codes.h"
#include "core/input_error.h"
#include "python/bindings.h"

namespace fvm::python {

std::vector<Eigen::Vector3d> PointsFrom(const DoubleArray& array, const std::string& what, bool finite) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    std::string shape;
    for (py::ssize_t k = 0; k < array.ndim(); ++k) shape += (k ? " x " : "") + std::to_string(array.shape(k));
    throw InputError(fmt::format("{}: expected an N x 3 array of x, y, z (mm), got shape ({})", what, shape));
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

void BindErrors(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Bad input: a file, value or combination to fix; the message names it, as the command line's does (its "
      "exit code 1).\n\nExample:\n    >>> try:\n    ...     fvm.read_surface('missing.x3p')\n"
      "    ... except fvm.InputError as e:\n    ...     print(e)";
  static py::exception<NotConvergedError> not_converged(m, "NotConvergedError", PyExc_RuntimeError);
  not_converged.doc() =
      "A solver stopped before it converged (the command line's exit code 3): the result must not be trusted as "
      "it is.\n\nExample:\n    >>> try:\n    ...     cal = fvm.calibrate('samples/bar17')\n"
      "    ... except fvm.NotConvergedError as e:\n    ...     print(e)";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const NotConvergedError& e) {
      not_converged(e.what());
    } catch (const std::invalid_argument& e) {
      // Library checks are bad input reaching a deeper layer: the command line reads them the same way (exit 1).
      input_error(e.what());
    }
  });
}

}  // namespace fvm::python

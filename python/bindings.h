#pragma once
// The pieces of the `fvm` Python module, one concept per file (surfaces, fits, calibration, machine, stitching,
// focus), and the conversions between numpy arrays and the libraries' Eigen and std types they share.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace fvm::python {

namespace py = pybind11;

// A float64 array, C order, converted from any numeric array (ints, float32, lists of lists).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

void BindErrors(py::module_& m);
void BindSurfaces(py::module_& m);
void BindFits(py::module_& m);
void BindCalibration(py::module_& m);
void BindMachine(py::module_& m);
void BindStitching(py::module_& m);
void BindTiles(py::module_& m);  // tiles_plan, tiles_simulate, tiles_synthesize (tiles.cc)
void BindFocus(py::module_& m);
void BindDiff(py::module_& m);      // fvm.diff (diff.cc)
void BindSimulate(py::module_& m);  // fvm.simulate_batch, fvm.simulate_scan (simulate.cc)
void BindResults(py::module_& m);  // fvm.Result and fvm.write_report (results.cc)
void BindTestPiece(py::module_& m);
void BindTracker(py::module_& m);
void BindStageJobs(py::module_& m);  // fvm.compare, fvm.diagnose, fvm.correct (stage_jobs.cc)

// A JSON document as Python dicts, lists, numbers, strings and None (results.cc).
py::object ToPython(const nlohmann::json& document);
py::object ToPython(const nlohmann::ordered_json& document);  // keys in the document's order
// An N x 3 array as points (mm). Throws InputError naming `what` for another shape or a non-finite coordinate when
// `finite` is asked.
std::vector<Eigen::Vector3d> PointsFrom(const DoubleArray& array, const std::string& what, bool finite = true);
// Points as an N x 3 float64 array.
py::array_t<double> PointsArray(const std::vector<Eigen::Vector3d>& points);
// A 3-vector as a numpy array of 3.
py::array_t<double> VectorArray(const Eigen::Vector3d& v);
// A rows x cols float64 array of row-major values (copied).
template <typename T>
py::array_t<double> GridArray(const std::vector<T>& values, int rows, int cols) {
  py::array_t<double> out({static_cast<py::ssize_t>(rows), static_cast<py::ssize_t>(cols)});
  double* data = out.mutable_data();
  for (std::size_t i = 0; i < values.size(); ++i) data[i] = static_cast<double>(values[i]);
  return out;
}

}  // namespace fvm::python

namespace fvm::stage {
struct IdentificationResult;
}

namespace fvm::python {
// Every coefficient of an identified model as the calibration file lists it: names, values (mm, rad), u, state,
// unit (calibration.cc).
py::dict ParameterDict(const stage::IdentificationResult& result);
// (name, reason) of each coefficient the data could not determine, fixed at 0.
std::vector<std::pair<std::string, std::string>> FixedCoefficients(const stage::IdentificationResult& result);
}  // namespace fvm::python

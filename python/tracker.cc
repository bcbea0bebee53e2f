// Laser trackers: points multilaterated from several stations' ranges (`fvm multilaterate`) and the simulated
// verification of a machine tool (`fvm simulate tracker`). Each returns fvm.Result, its summary the command's --json
// document (for the simulation: its truth.json) less the paths of its files.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "artefacts/io/tracker_readings.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "python/bindings.h"
#include "workflows/multilaterate_summary.h"
#include "workflows/simulate_tracker.h"

namespace fvm::python {
namespace {

workflows::Summary Multilaterate(const std::string& readings, const std::string& stations, bool self_calibrate, bool angles,
                                 const std::string& tracker, const std::string& nominal, const std::string& truth,
                                 const std::string& verify_readings, bool allow_unconverged) {
  workflows::MultilaterateOptions o;
  o.readings = readings, o.stations = stations, o.self_calibrate = self_calibrate, o.angles = angles, o.tracker = tracker;
  o.nominal = nominal, o.truth = truth;
  o.Check();
  py::gil_scoped_release release;
  const workflows::Multilateration m = workflows::Multilaterate(o);
  const auto nominal_points = workflows::NominalCoordinates(m, o.nominal);
  std::optional<stage::ResidualSummary> truth_error;
  if (!o.truth.empty()) truth_error = workflows::ErrorAgainstTruth(m, o.truth);
  if (!verify_readings.empty()) {
    artefacts::WriteTrackerReadings(verify_readings, workflows::VerifyReadings(m, o, nominal_points, o.nominal, verify_readings));
  }
  if (!m.result.converged && !allow_unconverged) {
    throw NotConvergedError("multilateration did not converge in " + std::to_string(m.result.iterations) + " iterations");
  }
  return workflows::Summarize(m, o, truth_error, o.truth, verify_readings.empty() ? "" : verify_readings + " (for fvm verify)");
}

// mesh:SX,SY,SZ | cloud:SX,SY,SZ | diagonals:N, as --points writes it.
workflows::PointPlan PlanFrom(const std::string& text, const std::string& what) {
  workflows::PointPlan plan;
  const size_t colon = text.find(':');
  plan.kind = text.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : text.substr(colon + 1);
  try {
    if (plan.kind == "diagonals") {
      plan.per_diagonal = std::stoi(rest);
    } else {
      size_t a = 0, b = 0;
      plan.step.x() = std::stod(rest, &a);
      plan.step.y() = std::stod(rest.substr(a + 1), &b);
      plan.step.z() = std::stod(rest.substr(a + b + 2));
    }
  } catch (const std::exception&) {
    throw InputError(what + " '" + text + "': use mesh:SX,SY,SZ, cloud:SX,SY,SZ (steps in mm) or diagonals:N");
  }
  return plan;
}

workflows::Summary SimulateTracker(const std::filesystem::path& output, const std::array<double, 6>& machine,
                                   const std::string& chain, const std::string& points, const std::array<double, 3>& tool,
                                   const std::array<double, 6>& pose, const std::string& errors,
                                   const std::optional<std::uint64_t>& seed, double mean_error_um, const std::string& tracker,
                                   double dwell_s, double feed_mm_min, const std::string& validation,
                                   const std::string& stations) {
  workflows::SimulateTrackerOptions o;
  o.machine.min = Eigen::Vector3d(machine[0], machine[1], machine[2]);
  o.machine.max = Eigen::Vector3d(machine[3], machine[4], machine[5]);
  o.chain = chain;
  o.points = PlanFrom(points, "points");
  o.tool = Eigen::Vector3d(tool.data());
  o.pose_mm = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  o.pose_euler_deg = Eigen::Vector3d(pose[3], pose[4], pose[5]);
  o.errors = errors, o.seed = seed, o.mean_error_um = mean_error_um, o.tracker = tracker;
  o.dwell_s = dwell_s, o.feed_mm_min = feed_mm_min, o.stations = stations;
  if (!validation.empty()) o.validation = PlanFrom(validation, "validation");
  o.Check();
  py::gil_scoped_release release;
  const workflows::SimulatedTracker simulated = workflows::SimulateTracker(o);
  workflows::WriteFiles(simulated, output);
  return workflows::Summarize(simulated, o, output.string());
}

}  // namespace

void BindTracker(py::module_& m) {
  const workflows::MultilaterateOptions d;
  m.def("multilaterate", &Multilaterate, py::arg("readings"), py::arg("stations") = d.stations,
        py::arg("self_calibrate") = d.self_calibrate, py::arg("angles") = d.angles, py::arg("tracker") = d.tracker,
        py::arg("nominal") = d.nominal, py::arg("truth") = d.truth, py::arg("verify_readings") = "",
        py::arg("allow_unconverged") = false,
        "Points located from the ranges (and with angles=True the angles) of several tracker stations, as `fvm "
        "multilaterate READINGS.csv` does: stations known (a stations JSON) or self-calibrated; truth: true positions "
        "to judge each point; verify_readings: also write the points as readings for fvm.verify. Returns an "
        "fvm.Result: its summary is the command's --json less `readings`.\n\nExample:\n"
        "    >>> r = fvm.multilaterate('net/readings.csv', stations='net/stations.json')\n    >>> r['range_rms_um']");
  const workflows::SimulateTrackerOptions s;
  m.def("simulate_tracker", &SimulateTracker, py::arg("output"),
        py::arg("machine") = std::array<double, 6>{s.machine.min.x(), s.machine.min.y(), s.machine.min.z(),
                                                   s.machine.max.x(), s.machine.max.y(), s.machine.max.z()},
        py::arg("chain") = s.chain, py::arg("points") = s.points.Text(),
        py::arg("tool") = std::array<double, 3>{s.tool.x(), s.tool.y(), s.tool.z()},
        py::arg("pose") = std::array<double, 6>{s.pose_mm.x(), s.pose_mm.y(), s.pose_mm.z(), s.pose_euler_deg.x(),
                                                s.pose_euler_deg.y(), s.pose_euler_deg.z()},
        py::arg("errors") = s.errors, py::arg("seed") = std::nullopt, py::arg("mean_error_um") = s.mean_error_um,
        py::arg("tracker") = s.tracker, py::arg("dwell_s") = s.dwell_s, py::arg("feed_mm_min") = s.feed_mm_min,
        py::arg("validation") = "", py::arg("stations") = s.stations,
        "Writes what `fvm simulate tracker -o OUTPUT` writes: the plan (points.csv, program.nc) and, with a seed or an "
        "errors file, the readings of a simulated machine (one tracker at pose X, Y, Z mm, A, B, C deg, or the "
        "stations of a JSON for fvm.multilaterate) with truth.json. machine: X0, Y0, Z0, X1, Y1, Z1 (mm); points "
        "and validation as --points: 'mesh:500,500,400', 'cloud:...', 'diagonals:N'. Returns an fvm.Result: its "
        "summary is truth.json, str() the line the command prints.\n\nExample:\n"
        "    >>> fvm.simulate_tracker('plan', seed=1, validation='mesh:250,250,200')");
}

}  // namespace fvm::python

// Machine tools: the volumetric verification from laser-tracker readings (`fvm verify DATA.csv --chain ... --order
// N --tool X,Y,Z`), the readings given as a CSV file or as arrays.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/core.h>

#include "artefacts/io/tracker_readings.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "python/bindings.h"
#include "stage/machine_verification.h"
#include "workflows/machine_problem.h"
#include "workflows/verify_machine.h"

namespace fvm::python {
namespace {

// A CSV path, or {"nominal": N x 3, "measured": N x 3 (tracker frame, Cartesian, mm), optional "ids" and "tool"
// (1, 2, ... into the tool offsets), "approach" (+x, ...)}.
artefacts::TrackerReadings ReadingsFrom(const py::object& arg, const std::string& what) {
  if (!py::isinstance<py::dict>(arg)) return artefacts::ReadTrackerReadings(py::str(arg).cast<std::string>());
  const py::dict d = arg.cast<py::dict>();
  for (const char* k : {"nominal", "measured"}) {
    if (!d.contains(k)) throw InputError(fmt::format("{}: no '{}' (give nominal and measured, N x 3 mm)", what, k));
  }
  const std::vector<Eigen::Vector3d> nominal = PointsFrom(d["nominal"].cast<DoubleArray>(), what + " nominal", false);
  const std::vector<Eigen::Vector3d> measured = PointsFrom(d["measured"].cast<DoubleArray>(), what + " measured", false);
  if (nominal.size() != measured.size()) {
    throw InputError(fmt::format("{}: {} nominal points and {} measured ones", what, nominal.size(), measured.size()));
  }
  if (nominal.empty()) throw InputError(what + ": no points");
  std::vector<std::string> ids;
  if (d.contains("ids")) {
    for (const py::handle id : d["ids"]) ids.push_back(py::str(id));
    if (ids.size() != nominal.size()) throw InputError(fmt::format("{}: {} ids for {} points", what, ids.size(), nominal.size()));
  }
  std::vector<std::string> approach(nominal.size());
  if (d.contains("approach")) {
    approach = d["approach"].cast<std::vector<std::string>>();
    if (approach.size() != nominal.size()) {
      throw InputError(fmt::format("{}: {} approach directions for {} points", what, approach.size(), nominal.size()));
    }
  }
  std::vector<int> tools(nominal.size(), 1);
  if (d.contains("tool")) {
    tools = d["tool"].cast<std::vector<int>>();
    if (tools.size() != nominal.size()) throw InputError(fmt::format("{}: {} tools for {} points", what, tools.size(), nominal.size()));
  }
  artefacts::TrackerReadings r;
  r.source = what;
  for (std::size_t i = 0; i < nominal.size(); ++i) {
    artefacts::TrackerReading p;
    p.id = ids.empty() ? fmt::format("P{:04d}", i + 1) : ids[i];
    p.nominal = nominal[i];
    p.measured = measured[i];
    p.approach = approach[i];
    p.tool = tools[i] - 1;
    p.line = static_cast<int>(i) + 1;
    r.points.push_back(p);
  }
  return r;  // checked as a file's readings are by workflows::MakeMachineProblem
}

// One tool offset (x, y, z) or a list of them.
std::vector<Eigen::Vector3d> ToolsFrom(const py::object& tool) {
  DoubleArray a = tool.cast<DoubleArray>();
  if (a.ndim() == 1) return PointsFrom(a.reshape({py::ssize_t{1}, a.shape(0)}), "tool");
  return PointsFrom(a, "tool");
}

py::dict ErrorDict(const stage::ResidualSummary& e) {
  return py::dict(py::arg("points") = e.count, py::arg("mean_um") = e.mean_um(), py::arg("max_um") = e.max_um(),
                  py::arg("min_um") = e.min_um());
}

py::dict PoseDict(const stage::Pose& p) {
  return py::dict(py::arg("translation") = VectorArray(p.translation), py::arg("rotation") = VectorArray(p.rotation));
}

py::dict Verify(const py::object& readings, const py::object& tool, const std::string& chain, const py::object& order,
                const std::string& basis, const py::object& validate, std::optional<std::pair<std::array<double, 3>, std::array<double, 3>>> pose,
                const std::string& tracker, bool unweighted, double max_error_mm, int threads, bool allow_unconverged) {
  workflows::MachineProblemOptions o;
  o.chain = chain;
  o.basis = basis;
  o.tools = ToolsFrom(tool);
  if (pose) {
    o.pose = stage::Pose{Eigen::Vector3d(pose->first.data()), Eigen::Vector3d(pose->second.data())};
  }
  o.tracker = tracker;
  o.unweighted = unweighted;
  o.max_error_mm = max_error_mm;
  o.threads = threads;
  workflows::VerifyMachineOptions job;
  const std::string order_text = py::str(order);
  if (order_text == "auto") {
    job.orders = {1, 2, 3};
  } else if (order_text == "1" || order_text == "2" || order_text == "3") {
    job.orders = {order_text[0] - '0'};
  } else {
    throw InputError("order " + order_text + ": use 1, 2, 3 or 'auto' (the best of the three)");
  }
  artefacts::TrackerReadings data = ReadingsFrom(readings, "readings");
  std::optional<artefacts::TrackerReadings> held_out;
  if (!validate.is_none()) held_out = ReadingsFrom(validate, "validate");
  std::optional<workflows::MachineVerification> verified;
  std::optional<workflows::MachineProblem> problem;
  {
    py::gil_scoped_release release;
    problem.emplace(workflows::MakeMachineProblem(o, std::move(data), std::move(held_out)));
    verified.emplace(workflows::VerifyMachine(*problem, job));
  }
  const workflows::OrderFit& chosen = verified->Chosen();
  const stage::VerificationResult& v = chosen.result;
  const stage::IdentificationResult& r = v.identified;
  if (!r.converged && !allow_unconverged) throw NotConvergedError(workflows::NotConvergedReason(r));
  py::dict out;
  out["order"] = chosen.order;
  out["points"] = problem->readings.points.size();
  out["weights"] = problem->WeightsName();
  out["initial"] = ErrorDict(v.initial);
  py::dict final_error = ErrorDict(v.final);
  final_error["rms_um"] = r.residual_summary.rms_um();
  out["final"] = final_error;
  if (chosen.validation) {
    out["validation"] = py::dict(py::arg("points") = problem->validation->points.size(),
                                 py::arg("initial") = ErrorDict(chosen.validation->before),
                                 py::arg("final") = ErrorDict(chosen.validation->after));
  } else {
    out["validation"] = py::none();
  }
  py::dict p = PoseDict(r.pose);
  p["estimated"] = !pose.has_value();
  p["initial"] = PoseDict(v.initial_pose);
  out["pose"] = p;
  out["parameters"] = ParameterDict(r);
  out["fixed"] = FixedCoefficients(r);
  out["residuals"] = PointsArray(r.residuals);
  out["converged"] = r.converged;
  if (verified->fits.size() > 1) {
    py::list orders;
    for (const workflows::OrderFit& f : verified->fits) {
      orders.append(py::dict(py::arg("order") = f.order, py::arg("bic") = f.bic, py::arg("final") = ErrorDict(f.result.final)));
    }
    out["orders"] = orders;
    out["order_chosen_by"] = verified->ChosenBy();
  }
  return out;
}

}  // namespace

void BindMachine(py::module_& m) {
  m.def("verify", &Verify, py::arg("readings"), py::arg("tool") = std::array<double, 3>{0, 0, 0},
        py::arg("chain") = "XFYZ", py::arg("order") = 3, py::arg("basis") = "legendre",
        py::arg("validate") = py::none(), py::arg("pose") = std::nullopt, py::arg("tracker") = "published",
        py::arg("unweighted") = false, py::arg("max_error_mm") = 0.0, py::arg("threads") = 0,
        py::arg("allow_unconverged") = false,
        "The volumetric verification of a machine tool from laser-tracker readings, as `fvm verify DATA.csv "
        "--chain XFYZ --order N --tool X,Y,Z` does. readings (and validate): a CSV path, or a dict {'nominal': "
        "N x 3, 'measured': N x 3 (tracker frame, mm), optional 'ids', 'tool' (1, 2, ...), 'approach'}; tool: one offset "
        "(x, y, z) mm or a list of them; order 1-3 or 'auto'; pose: ((tx, ty, tz) mm, rotation vector rad) to hold "
        "the tracker's pose, else it is estimated. Returns a dict: order, initial / final volumetric errors (um), "
        "validation, pose, parameters (names, values, u), fixed, residuals (N x 3 mm). Raises fvm.InputError with "
        "the command line's messages, fvm.NotConvergedError when the identification did not converge.\n\n"
        "Example:\n    >>> v = fvm.verify('tracker.csv', tool=(0, 0, 150), order=2)\n"
        "    >>> v['initial']['mean_um'], v['final']['mean_um']");
}

}  // namespace fvm::python

// Machine tools: the volumetric verification from laser-tracker readings (`fvm verify DATA.csv --chain ... --order
// N --tool X,Y,Z`) and its Monte Carlo uncertainty (`fvm uncertainty`), the readings given as a CSV file or as
// arrays. Each returns fvm.Result, its summary the command's --json document less the paths of its files.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "core/exit_codes.h"
#include "python/machine_arguments.h"
#include "stage/machine_verification.h"
#include "workflows/uncertainty_summary.h"
#include "workflows/verify_summary.h"

namespace fvm::python {
namespace {

// fvm.Verification: fvm verify's summary with the identified coefficients and residuals as arrays.
struct Verification : workflows::Summary {
  stage::IdentificationResult identified;
};

Verification Verify(const py::object& readings, const py::object& tool, const std::string& chain, const py::object& order,
                    const std::string& basis, const py::object& validate, const py::object& pose, const py::object& machine,
                    const std::string& tracker, bool unweighted, double max_error_mm, int threads, bool allow_unconverged) {
  workflows::VerifyMachineOptions options;
  MachineKeywords k{readings, tool, validate, pose, chain, basis, tracker, unweighted, max_error_mm, threads};
  k.machine = machine;
  options.machine = MachineOptionsFrom(k, options.machine);
  options.orders = workflows::ParseOrders(py::str(order));
  options.Check();
  const workflows::MachineProblem problem = MachineProblemFrom(k, options.machine);
  std::optional<workflows::MachineVerification> verified;
  {
    py::gil_scoped_release release;
    verified.emplace(workflows::VerifyMachine(problem, options));
  }
  const stage::IdentificationResult& r = verified->Chosen().result.identified;
  if (!r.converged && !allow_unconverged) throw NotConvergedError(workflows::NotConvergedReason(r));
  return {workflows::Summarize(problem, options, *verified), r};
}

workflows::Summary Uncertainty(const py::object& data, const py::object& tool, const std::string& chain, int order,
                               const std::string& basis, const py::object& validate, const py::object& pose,
                               const py::object& machine, const std::string& tracker, bool unweighted, double max_error_mm, int runs,
                               std::uint64_t seed, double u_cal_um, double temperature_c, double cte_per_k, double k,
                               const std::string& model, const std::string& terms, double centre_noise_um,
                               const std::optional<std::array<double, 6>>& place_tracker, int place_steps,
                               int place_confirm, int threads) {
  workflows::UncertaintyOptions o;
  MachineKeywords keywords{data, tool, validate, pose, chain, basis, tracker, unweighted, max_error_mm, threads};
  keywords.machine = machine;
  o.machine = MachineOptionsFrom(keywords, o.machine);
  o.order = order;
  o.monte_carlo.runs = runs;
  o.monte_carlo.seed = seed;
  o.monte_carlo.threads = threads;
  o.u_cal_um = u_cal_um, o.temperature_c = temperature_c, o.cte_per_k = cte_per_k, o.k = k;
  o.stage.model.model = model;
  o.stage.model.terms = terms;
  o.stage.centre_noise_um = centre_noise_um;
  o.stage.settings.threads = threads;
  o.place_tracker = place_tracker;
  o.place_tracker_name = "place_tracker";
  o.place_steps = place_steps, o.place_confirm = place_confirm;
  o.Check();
  if (!py::isinstance<py::dict>(data) && std::filesystem::is_directory(o.machine.data)) {
    if (!validate.is_none() || place_tracker) {
      throw InputError(o.machine.data + " is a batch directory: validate and place_tracker are for tracker readings");
    }
    o.stage.batch = o.machine.data;
    py::gil_scoped_release release;
    const workflows::StageReference reference = workflows::IdentifyStageReference(o.stage);
    return workflows::Summarize(o, reference, workflows::RunStageMonteCarlo(o.stage, reference, o.monte_carlo, o.Budget()));
  }
  const workflows::MachineProblem problem = MachineProblemFrom(keywords, o.machine);
  py::gil_scoped_release release;
  const workflows::MachineReference reference = workflows::IdentifyMachineReference(problem, o.order);
  if (o.place_tracker) return workflows::Summarize(problem, o, workflows::PlaceTracker(problem, reference, o.Placement()));
  return workflows::Summarize(problem, o, reference, workflows::RunMachineMonteCarlo(problem, reference, o.monte_carlo, o.Budget()));
}

}  // namespace

void BindMachine(py::module_& m) {
  py::class_<Verification, workflows::Summary>(
      m, "Verification",
      "fvm verify's result: an fvm.Result (summary: the --json document; fvm.write_report writes --report's page) "
      "with the identified coefficients as arrays.")
      .def_property_readonly("parameters", [](const Verification& v) { return ParameterDict(v.identified); },
                             "dict of names, values (numpy, mm and rad), u, state and unit of every coefficient")
      .def_property_readonly("residuals", [](const Verification& v) { return PointsArray(v.identified.residuals); },
                             "N x 3 residual of each reading after the fit (mm)");
  const workflows::VerifyMachineOptions verify;
  const workflows::MachineProblemOptions& d = verify.machine;
  m.def("verify", &Verify, py::arg("readings"), py::arg("tool") = std::array<double, 3>{0, 0, 0},
        py::arg("chain") = d.chain, py::arg("order") = verify.orders.front(), py::arg("basis") = d.basis,
        py::arg("validate") = py::none(), py::arg("pose") = py::none(), py::arg("machine") = py::none(),
        py::arg("tracker") = d.tracker,
        py::arg("unweighted") = d.unweighted, py::arg("max_error_mm") = d.max_error_mm, py::arg("threads") = d.threads,
        py::arg("allow_unconverged") = false,
        "The volumetric verification of a machine tool from laser-tracker readings, as `fvm verify DATA.csv "
        "--chain XFYZ --order N --tool X,Y,Z` does. readings (and validate): a CSV path, or a dict {'nominal': "
        "N x 3, 'measured': N x 3 (tracker frame, mm), optional 'ids', 'tool' (1, 2, ...), 'approach'}; tool: one offset "
        "(x, y, z) mm or a list of them; order 1-3 or 'auto'; pose: (X, Y, Z mm, A, B, C XYZ Euler deg) as --pose, or "
        "((tx, ty, tz) mm, rotation vector rad), to hold the tracker's pose, else it is estimated; machine: the travel "
        "(X0, Y0, Z0, X1, Y1, Z1) mm, else the span of the points. Returns an "
        "fvm.Verification: its summary is `fvm verify --json` (initial / final volumetric errors in um, validation, "
        "pose with Euler angles and uncertainties, fixed, parameters, plausibility), .parameters and .residuals arrays; "
        "fvm.write_report(v, dir) writes --report's page. Raises fvm.InputError with the command line's messages "
        "(an implausible result among them), fvm.NotConvergedError when the identification did not converge.\n\n"
        "Example:\n    >>> v = fvm.verify('tracker.csv', tool=(0, 0, 150), order=2)\n"
        "    >>> v['initial']['mean_um'], v['final']['mean_um']");

  const workflows::UncertaintyOptions u;
  m.def("uncertainty", &Uncertainty, py::arg("data"), py::arg("tool") = std::array<double, 3>{0, 0, 0},
        py::arg("chain") = u.machine.chain, py::arg("order") = u.order, py::arg("basis") = u.machine.basis,
        py::arg("validate") = py::none(), py::arg("pose") = py::none(), py::arg("machine") = py::none(),
        py::arg("tracker") = u.machine.tracker,
        py::arg("unweighted") = u.machine.unweighted, py::arg("max_error_mm") = u.machine.max_error_mm,
        py::arg("runs") = u.monte_carlo.runs, py::arg("seed") = u.monte_carlo.seed, py::arg("u_cal_um") = u.u_cal_um,
        py::arg("temperature_c") = u.temperature_c, py::arg("cte_per_k") = u.cte_per_k, py::arg("k") = u.k,
        py::arg("model") = u.stage.model.model, py::arg("terms") = u.stage.model.terms,
        py::arg("centre_noise_um") = u.stage.centre_noise_um, py::arg("place_tracker") = std::nullopt,
        py::arg("place_steps") = u.place_steps, py::arg("place_confirm") = u.place_confirm, py::arg("threads") = 0,
        "Monte Carlo uncertainty [GUM Supplement 1] as `fvm uncertainty` computes it: of a machine verification "
        "(data: tracker readings, keywords as fvm.verify's), of a microscope stage's calibration (data: a batch "
        "directory; model, terms, centre_noise_um), or the ranking of tracker positions in a box (place_tracker: "
        "X0, Y0, Z0, X1, Y1, Z1 mm). Run i draws from a stream seeded by (seed, i): the same bits for any thread "
        "count. Returns an fvm.Result: its summary is `fvm uncertainty --json`; fvm.write_report writes --report's "
        "page.\n\nExample:\n    >>> u = fvm.uncertainty('plan/readings.csv', tool=(0, 0, 100), order=2, runs=200)\n"
        "    >>> u['budget']['U_um']");
}

}  // namespace fvm::python

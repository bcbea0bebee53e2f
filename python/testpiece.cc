// The machined test piece of [Lorente 2021]: its design (`fvm testpiece design`), a machine verified from its CMM
// measurement (`fvm testpiece verify`), and its simulation (`fvm simulate testpiece`). Each returns fvm.Result, its
// summary the command's --json document less the paths of its files.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "artefacts/geometry/machined_piece.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "python/machine_arguments.h"
#include "workflows/machined_piece_summary.h"
#include "workflows/simulate_testpiece.h"

namespace fvm::python {
namespace {

workflows::Summary Design(const std::string& piece) {
  const artefacts::MachinedPieceDescription d = piece.empty() ? artefacts::PublishedMachinedPiece() : artefacts::ReadMachinedPiece(piece);
  const std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(d);
  if (points.empty()) throw InputError(piece + ": the piece has no probe points; give each feature \"points\"");
  return workflows::SummarizeDesign(d, points);
}

workflows::Summary VerifyPiece(const py::object& data, const py::object& tool, const std::string& chain, int order,
                               const std::string& basis, const py::object& validate, const std::string& nominal,
                               double max_error_mm, int threads, bool allow_unconverged) {
  workflows::MachinedPieceVerifyOptions o;
  const MachineKeywords k{data, tool, validate, py::none(), chain, basis, o.machine.tracker, o.machine.unweighted,
                          max_error_mm, threads};
  o.machine = MachineOptionsFrom(k, o.machine);
  o.order = order;
  o.nominal = nominal;
  o.Check();
  const workflows::MachineProblem problem = MachineProblemFrom(k, o.machine);
  py::gil_scoped_release release;
  const workflows::MachinedPieceVerifyResult verified = workflows::VerifyMachinedPiece(problem, o);
  const stage::IdentificationResult& r = verified.verification.result.identified;
  if (!r.converged && !allow_unconverged) throw NotConvergedError(workflows::NotConvergedReason(r));
  return workflows::Summarize(problem, o, verified);
}

workflows::Summary SimulatePiece(const std::filesystem::path& output, const std::string& piece, const std::string& errors,
                                 double mean_error_um, const std::string& points, const std::string& chain,
                                 const std::array<double, 3>& tool, const std::optional<std::array<double, 6>>& datum,
                                 std::uint64_t seed, double noise_um, bool proposed_series,
                                 const std::optional<std::array<double, 3>>& validation) {
  workflows::SimulateTestPieceOptions o;
  o.piece = piece, o.errors = errors, o.mean_error_um = mean_error_um, o.points = points, o.chain = chain;
  o.tool = Eigen::Vector3d(tool.data());
  if (datum) {
    const auto& v = *datum;
    o.datum = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
  }
  o.seed = seed, o.noise_um = noise_um, o.proposed_series = proposed_series;
  if (validation) o.validation_step = Eigen::Vector3d(validation->data());
  o.Check();
  py::gil_scoped_release release;
  const workflows::SimulatedTestPiece simulated = workflows::SimulateTestPiece(o);
  workflows::WriteFiles(simulated, output);
  return workflows::Summarize(simulated, o, output.string());
}

}  // namespace

void BindTestPiece(py::module_& m) {
  m.def("testpiece_design", &Design, py::arg("piece") = "",
        "The probe points of a test piece, as `fvm testpiece design [PIECE.json] --json` counts them (piece: a "
        "description JSON; empty: the published piece of [Lorente 2021]). Returns an fvm.Result.\n\n"
        "Example:\n    >>> fvm.testpiece_design()['points']");
  const workflows::MachinedPieceVerifyOptions v;
  m.def("testpiece_verify", &VerifyPiece, py::arg("data"), py::arg("tool") = std::array<double, 3>{0, 0, 100},
        py::arg("chain") = v.machine.chain, py::arg("order") = v.order, py::arg("basis") = v.machine.basis,
        py::arg("validate") = py::none(), py::arg("nominal") = v.nominal, py::arg("max_error_mm") = v.machine.max_error_mm,
        py::arg("threads") = 0, py::arg("allow_unconverged") = false,
        "A machine verified from the CMM measurement of its test piece (data: id,x,y,z,xm,ym,zm, or arrays as "
        "fvm.verify takes), as `fvm testpiece verify` does: the iteration log, which errors the points (with nominal: "
        "the series X1..Z3 alone) recover. Returns an fvm.Result: its summary is the command's --json; "
        "fvm.write_report writes --report's page.\n\nExample:\n"
        "    >>> r = fvm.testpiece_verify('tp/measured.csv', order=2, nominal='tp/nominal.csv')");
  const workflows::SimulateTestPieceOptions s;
  m.def("simulate_testpiece", &SimulatePiece, py::arg("output"), py::arg("piece") = s.piece, py::arg("errors") = s.errors,
        py::arg("mean_error_um") = s.mean_error_um, py::arg("points") = s.points, py::arg("chain") = s.chain,
        py::arg("tool") = std::array<double, 3>{s.tool.x(), s.tool.y(), s.tool.z()}, py::arg("datum") = std::nullopt,
        py::arg("seed") = s.seed, py::arg("noise_um") = s.noise_um, py::arg("proposed_series") = s.proposed_series,
        py::arg("validation") = std::nullopt,
        "Writes what `fvm simulate testpiece -o OUTPUT` writes (nominal.csv, measured.csv, truth.json, with "
        "validation=(sx, sy, sz) validation.csv); datum: X, Y, Z mm, A, B, C deg (default 20,-15,5,0.05,-0.1,12). "
        "Returns an fvm.Result (its summary: the command's --json less output).\n\n"
        "Example:\n    >>> fvm.simulate_testpiece('tp', validation=(30, 30, 30))");
}

}  // namespace fvm::python

#include "python/machine_arguments.h"

#include <pybind11/stl.h>

#include <fmt/core.h>
#include <fmt/ranges.h>

#include "core/input_error.h"

namespace fvm::python {
namespace {

// One tool offset (x, y, z) or a list of them.
std::vector<Eigen::Vector3d> ToolsFrom(const py::object& tool) {
  DoubleArray a = tool.cast<DoubleArray>();
  if (a.ndim() == 1) return PointsFrom(a.reshape({py::ssize_t{1}, a.shape(0)}), "tool");
  return PointsFrom(a, "tool");
}

// ((tx, ty, tz) mm, rotation vector rad), or X, Y, Z (mm), A, B, C (XYZ Euler, deg) as --pose writes it.
stage::Pose PoseFrom(const py::object& pose) {
  const py::sequence items = pose.cast<py::sequence>();
  if (items.size() == 6) {
    const std::vector<double> v = pose.cast<std::vector<double>>();
    return stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
  }
  if (items.size() != 2) throw InputError("pose: give X,Y,Z (mm), A,B,C (XYZ Euler, deg), or (translation, rotation vector)");
  const auto t = items[0].cast<std::array<double, 3>>(), r = items[1].cast<std::array<double, 3>>();
  return stage::Pose{Eigen::Vector3d(t.data()), Eigen::Vector3d(r.data())};
}

}  // namespace

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
  const auto column = [&](const char* key, auto fill) {
    using T = typename decltype(fill)::value_type;
    if (!d.contains(key)) return fill;
    std::vector<T> values = d[key].template cast<std::vector<T>>();
    if (values.size() != nominal.size()) throw InputError(fmt::format("{}: {} {} for {} points", what, values.size(), key, nominal.size()));
    return values;
  };
  std::vector<std::string> ids;
  if (d.contains("ids")) {
    for (const py::handle id : d["ids"]) ids.push_back(py::str(id));
    if (ids.size() != nominal.size()) throw InputError(fmt::format("{}: {} ids for {} points", what, ids.size(), nominal.size()));
  }
  const std::vector<std::string> approach = column("approach", std::vector<std::string>(nominal.size()));
  const std::vector<int> tools = column("tool", std::vector<int>(nominal.size(), 1));
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

workflows::MachineProblemOptions MachineOptionsFrom(const MachineKeywords& k, workflows::MachineProblemOptions o) {
  if (!py::isinstance<py::dict>(k.readings)) o.data = py::str(k.readings);
  if (!k.validate.is_none() && !py::isinstance<py::dict>(k.validate)) o.validate = py::str(k.validate);
  o.chain = k.chain;
  o.basis = k.basis;
  if (!k.tool.is_none()) o.tools = ToolsFrom(k.tool);
  if (!k.pose.is_none()) o.pose = PoseFrom(k.pose);
  if (!k.machine.is_none()) {
    const auto box = k.machine.cast<std::array<double, 6>>();
    o.travel = artefacts::Workspace{Eigen::Vector3d(box[0], box[1], box[2]), Eigen::Vector3d(box[3], box[4], box[5])};
    o.travel_name = fmt::format("machine ({})", fmt::join(box, ", "));
  }
  o.tracker = k.tracker;
  o.unweighted = k.unweighted;
  o.max_error_mm = k.max_error_mm;
  o.threads = k.threads;
  o.Check();
  return o;
}

workflows::MachineProblem MachineProblemFrom(const MachineKeywords& k, const workflows::MachineProblemOptions& options) {
  artefacts::TrackerReadings data = ReadingsFrom(k.readings, "readings");
  std::optional<artefacts::TrackerReadings> held_out;
  if (!k.validate.is_none()) held_out = ReadingsFrom(k.validate, "validate");
  py::gil_scoped_release release;
  return workflows::MakeMachineProblem(options, std::move(data), std::move(held_out));
}

}  // namespace fvm::python

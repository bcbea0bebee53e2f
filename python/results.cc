// fvm.Result: a job's summary (workflows/summary.h) as Python sees it. `result.summary` is the job's --json
// document as dicts, lists and numbers (equal to what `fvm <job> --json` prints for the same input, less the paths
// of the command's files), `str(result)` the text the command prints, and fvm.write_report(result, DIR) writes the
// files `--report DIR` writes.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "core/input_error.h"
#include "python/bindings.h"
#include "workflows/summary.h"

namespace fvm::python {

py::object ToPython(const nlohmann::json& document) {
  // Through Python's own JSON reader: the numbers are the same doubles (nlohmann writes the shortest text that
  // reads back exactly), and NaN is None on both sides.
  return py::module_::import("json").attr("loads")(document.dump());
}

py::object ToPython(const nlohmann::ordered_json& document) {
  return py::module_::import("json").attr("loads")(document.dump());
}

void BindResults(py::module_& m) {
  py::class_<workflows::Summary>(m, "Result",
                                 "What a job found: `summary` (a dict, the command's --json document), str() the text "
                                 "the command prints, and fvm.write_report(result, dir) for its HTML report.")
      .def_property_readonly(
          "summary", [](const workflows::Summary& s) { return ToPython(s.json); },
          "The job's --json document as dicts, lists and numbers (units in the key names: _mm, _um, _urad).")
      .def_property_readonly(
          "has_report", [](const workflows::Summary& s) { return s.report.has_value(); },
          "Whether fvm.write_report can write a report for this result.")
      .def("__getitem__", [](const workflows::Summary& s, const std::string& key) -> py::object {
        if (!s.json.is_object() || !s.json.contains(key)) throw py::key_error(key);
        return ToPython(s.json.at(key));
      })
      .def("keys", [](const workflows::Summary& s) {
        std::vector<std::string> keys;
        if (s.json.is_object()) {
          for (const auto& item : s.json.items()) keys.push_back(item.key());
        }
        return keys;
      })
      .def("__str__", [](const workflows::Summary& s) { return s.text; })
      .def("__repr__", [](const workflows::Summary& s) { return s.text; });

  m.def(
      "write_report",
      [](const workflows::Summary& result, const std::filesystem::path& dir) {
        if (!result.report) throw InputError("this result has no report (its job writes none)");
        py::gil_scoped_release release;
        report::Write(dir, *result.report);
      },
      py::arg("result"), py::arg("dir"),
      "Writes the HTML report of a result into dir (index.html and its SVG plots), the same files as the command's "
      "--report DIR.\n\nExample:\n    >>> r = fvm.diagnose('samples/bar17', model=27)\n"
      "    >>> fvm.write_report(r, 'diagnosis-report')");
}

}  // namespace fvm::python

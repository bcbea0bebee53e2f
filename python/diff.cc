// fvm.diff: how far a test export of an artefact is from a reference export, calotte by calotte and as distances
// (`fvm diff`, workflows/diff.h).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "python/bindings.h"
#include "workflows/diff.h"

namespace fvm::python {

void BindDiff(py::module_& m) {
  const workflows::DiffOptions defaults;
  m.def(
      "diff",
      [](const std::filesystem::path& ref, const std::filesystem::path& test, const std::string& pairs, bool xy) {
        const workflows::DiffOptions options{pairs, xy};
        options.Check();
        py::gil_scoped_release release;
        return workflows::Summarize(workflows::DiffFiles(ref.string(), test.string(), options));
      },
      py::arg("ref"), py::arg("test"), py::kw_only(), py::arg("pairs") = defaults.pairs, py::arg("xy") = defaults.xy,
      "Per-calotte differences TEST - REF (dx_um, dy_um, dz_um, d_um) of two centre exports and, for pairs of "
      "calottes, their distance in each (mm) and its change (um), as `fvm diff REF TEST`. pairs: 'a:b,...' "
      "(default: the first common calotte with every other one); xy: distances in the XY plane. Returns an "
      "fvm.Result whose summary equals `fvm diff --json` less the paths; calottes in one file only are listed in "
      "only_in_ref / only_in_test.\n\nExample:\n    >>> r = fvm.diff('a.csv', 'b.csv', pairs='1:6', xy=True)\n"
      "    >>> r['pairs'][0]['diff_um']");
}

}  // namespace fvm::python

// The stage jobs beside calibrate: fvm.compare (every model order side by side), fvm.diagnose (the discrepancy
// workflow) and fvm.correct (a centre export, a scan, a tile layout or a machine's point list corrected with a
// model file, as `fvm correct` does), and fvm.diagnose_tiles (the field distortion's test on tiles, as `fvm diagnose
// --layout/--scan`). Each returns fvm.Result: the command's --json document (less the paths of its files), its printed
// text and, for diagnose, its report (fvm.write_report).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "artefacts/io/batch.h"
#include "core/version.h"
#include "python/bindings.h"
#include "workflows/compare_models.h"
#include "workflows/correct_files.h"
#include "workflows/diagnose.h"
#include "workflows/diagnose_tiles.h"

namespace fvm::python {
namespace {

// A model named as Python gives it: 27 or "27".
std::string ModelName(const py::object& model) { return py::str(model); }

// "9,15" or [9, 15] or ["9", "15"], as --models takes them.
std::vector<std::string> ModelNames(const py::object& models) {
  std::vector<std::string> names;
  if (py::isinstance<py::str>(models)) {
    const std::string text = py::str(models);
    std::size_t start = 0;
    while (start <= text.size()) {
      const std::size_t end = std::min(text.find(',', start), text.size());
      names.push_back(text.substr(start, end - start));
      start = end + 1;
    }
    return names;
  }
  for (const py::handle item : models) names.push_back(py::str(item));
  return names;
}

workflows::IdentifySettings Settings(workflows::IdentifySettings s, const std::string& anchor, const std::string& stitched_frame,
                                     const std::string& loss, double loss_scale_um, int threads) {
  s.anchor = anchor;
  s.stitched_frame = stitched_frame;
  s.loss = loss;
  s.loss_scale_um = loss_scale_um;
  s.threads = threads;
  return s;
}

workflows::Summary Compare(const std::filesystem::path& batch, const py::object& models, const std::string& anchor,
                           const std::string& stitched_frame, const std::string& loss, double loss_scale_um, int threads) {
  workflows::CompareOptions options;
  options.models = ModelNames(models);
  options.settings = Settings(options.settings, anchor, stitched_frame, loss, loss_scale_um, threads);
  options.Check();
  py::gil_scoped_release release;
  const artefacts::Batch b = artefacts::ReadBatch(batch);
  return workflows::Summarize(workflows::CompareModels(b, options), options, batch.string());
}

workflows::Summary Diagnose(const std::filesystem::path& batch, const py::object& model, const std::string& terms, double alpha,
                            const std::string& anchor, const std::string& stitched_frame, const std::string& loss,
                            double loss_scale_um, int threads) {
  workflows::DiagnoseOptions options;
  options.model = {ModelName(model), terms};
  options.alpha = alpha;
  options.settings = Settings(options.settings, anchor, stitched_frame, loss, loss_scale_um, threads);
  options.Check();
  py::gil_scoped_release release;
  const artefacts::Batch b = artefacts::ReadBatch(batch);
  return workflows::Summarize(workflows::DiagnoseBatch(b, options), options, batch.string());
}

workflows::Summary DiagnoseTiles(const std::optional<std::filesystem::path>& layout, const std::vector<std::filesystem::path>& scans,
                                 double overlap, double pixel_mm, int order, double alpha, int threads) {
  workflows::TileDiagnoseOptions options;
  if (layout) options.layout = layout->string();
  for (const auto& scan : scans) options.scans.push_back(scan.string());
  options.overlap = overlap >= 1.0 ? overlap / 100.0 : overlap;  // as --overlap reads 10 and 0.1
  options.pixel_mm = pixel_mm;
  options.order = order;
  options.alpha = alpha;
  options.threads = threads;
  options.Check();
  py::gil_scoped_release release;
  return workflows::Summarize(workflows::DiagnoseTiles(options), options);
}

struct ReadKeywords {
  double pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm;
  std::optional<double> invalid;
  std::string unit;
};

workflows::Summary Correct(workflows::CorrectOptions options, const std::optional<std::array<double, 3>>& origin,
                           const ReadKeywords& read) {
  if (origin) options.origin_mm = Eigen::Vector3d((*origin)[0], (*origin)[1], (*origin)[2]);
  options.read.image = {read.pixel_mm, read.pixel_y_mm, read.z_scale_mm, read.z_offset_mm, read.invalid};
  if (read.unit != "mm" && read.unit != "um" && read.unit != "m") {
    throw InputError("unit: '" + read.unit + "' is not one of mm, um, m");
  }
  options.read.cloud.mm_per_unit = read.unit == "m" ? 1000.0 : read.unit == "um" ? 0.001 : 1.0;
  options.version = Version();
  options.Check();
  py::gil_scoped_release release;
  return workflows::CorrectFiles(options).summary;
}

}  // namespace

void BindStageJobs(py::module_& m) {
  const workflows::CompareOptions compare;
  const workflows::DiagnoseOptions diagnose;
  const workflows::CorrectOptions correct;
  m.def("compare", &Compare, py::arg("batch"), py::arg("models") = compare.models, py::arg("anchor") = compare.settings.anchor,
        py::arg("stitched_frame") = compare.settings.stitched_frame, py::arg("loss") = compare.settings.loss,
        py::arg("loss_scale_um") = compare.settings.loss_scale_um, py::arg("threads") = compare.settings.threads,
        "Every model order side by side on a batch directory, judged on held-out placements, and which one to trust, "
        "as `fvm compare BATCH` does. Returns fvm.Result (summary: the --json document less 'batch').\n\nExample:\n"
        "    >>> r = fvm.compare('samples/bar17', models=[15, 27])\n    >>> r['recommendation']");
  m.def("diagnose", &Diagnose, py::arg("batch"), py::arg("model") = diagnose.model.model, py::arg("terms") = diagnose.model.terms,
        py::arg("alpha") = diagnose.alpha, py::arg("anchor") = diagnose.settings.anchor,
        py::arg("stitched_frame") = diagnose.settings.stitched_frame, py::arg("loss") = diagnose.settings.loss,
        py::arg("loss_scale_um") = diagnose.settings.loss_scale_um, py::arg("threads") = diagnose.settings.threads,
        "The discrepancy workflow on a batch directory, as `fvm diagnose BATCH --model N`: which effect the model "
        "misses, added step by step while held-out placements confirm it. Returns fvm.Result (summary: the --json "
        "document less 'batch'); fvm.write_report(result, dir) writes what --report DIR writes.\n\nExample:\n"
        "    >>> r = fvm.diagnose('samples/bar17', model=27)\n    >>> r['effect'], r['after']['mean_um']");
  const workflows::TileDiagnoseOptions tiles;
  m.def("diagnose_tiles", &DiagnoseTiles, py::arg("layout") = py::none(), py::arg("scans") = std::vector<std::filesystem::path>{},
        py::arg("overlap") = tiles.overlap, py::arg("pixel_mm") = tiles.pixel_mm, py::arg("order") = tiles.order,
        py::arg("alpha") = tiles.alpha, py::arg("threads") = tiles.threads,
        "Whether the overlaps of a tile grid (layout, with overlap) or of calibration scans (scans, with pixel_mm) "
        "show the objective's field distortion, as `fvm diagnose --layout L.csv --overlap PCT` / `--scan L.csv ... "
        "--pixel-mm P`: the rigid and the field model fitted on the same correspondences, compared by an F test and "
        "the BIC. Returns fvm.Result (summary: the --json document less 'layout').\n\nExample:\n"
        "    >>> r = fvm.diagnose_tiles(scans=['s/row.csv', 's/column.csv', 's/diagonal.csv'], pixel_mm=0.011)\n"
        "    >>> r['effect'], r['before']['rms_px'], r['after']['rms_px']");
  m.def(
      "correct",
      [](const std::string& calibration, const std::string& input, const std::string& output, const std::string& layout,
         const std::string& frame, const std::string& stitched_frame, const std::optional<std::array<double, 3>>& origin,
         double resample, bool extrapolate, double pixel_mm, double pixel_y_mm, double z_scale_mm, double z_offset_mm,
         std::optional<double> invalid, const std::string& unit, int threads) {
        workflows::CorrectOptions o;
        o.calibration = calibration;
        o.input = input;
        o.output = output;
        o.layout = layout;
        o.frame = frame;
        o.stitched_frame = stitched_frame;
        o.resample_mm = resample;
        o.extrapolate = extrapolate;
        o.threads = threads;
        return Correct(o, origin, {pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm, invalid, unit});
      },
      py::arg("calibration"), py::arg("input") = correct.input, py::arg("output") = correct.output,
      py::arg("layout") = correct.layout, py::arg("frame") = correct.frame, py::arg("stitched_frame") = correct.stitched_frame,
      py::arg("origin") = std::nullopt, py::arg("resample") = correct.resample_mm, py::arg("extrapolate") = correct.extrapolate,
      py::arg("pixel_mm") = 0.0, py::arg("pixel_y_mm") = 0.0, py::arg("z_scale_mm") = 0.0, py::arg("z_offset_mm") = 0.0,
      py::arg("invalid") = std::nullopt, py::arg("unit") = "mm", py::arg("threads") = correct.threads,
      "Corrects a file with a model file, as `fvm correct --calibration CAL IN -o OUT`: a stitching-free centre "
      "export, a scan (point cloud XYZ/PLY/PCD, height map X3P/AL3D/TIFF; resample=PIXEL_MM for a height map again, "
      "origin=(x, y, z) for a file whose origin is not the stage's), the tiles of a layout (layout=L.csv, output a "
      "directory), or with a machine model (fvm verify) a list of nominal points into a compensation table. Writes "
      "output; returns fvm.Result (summary: the --json document less 'input', 'output' and 'layout').\n\nExample:\n"
      "    >>> r = fvm.correct('cal.json', 'scan.x3p', 'scan.ply')\n    >>> r['largest_shift_um']");
}

}  // namespace fvm::python

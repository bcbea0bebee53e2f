// The main job: a stage model identified from a batch of stitched / stitching-free centre pairs, or from stitched
// calibration scans (`fvm calibrate [--scan]`), judged on the validation placements, and used to compensate points
// (`fvm correct`); read from and saved to the calibration file the command line writes and reads. The job and its
// summary are the library's (workflows/calibrate_job.h, workflows/calibration_summary.h): a Calibration is an
// fvm.Result whose summary is the command's --json document, the file save() writes the one -o writes.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <fmt/core.h>
#include <fstream>

#include "artefacts/io/batch.h"
#include "artefacts/io/raw_export_batch.h"
#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "python/bindings.h"
#include "stage/calibration.h"
#include "stage/io/calibration_file.h"
#include "workflows/calibrate_job.h"
#include "workflows/calibration_summary.h"
#include "workflows/summary.h"

namespace fvm::python {
namespace {

// What Python holds: the job's summary (the --json document, the printed text, the report's data), the
// identification (the calibration and what the file records of the fit), and the judged set's figures for plots.
struct PyCalibration : workflows::Summary {
  PyCalibration(workflows::Summary summary, stage::IdentificationResult r, bool file, py::dict j)
      : workflows::Summary(std::move(summary)), result(std::move(r)), from_file(file), judged(std::move(j)) {}
  stage::IdentificationResult result;
  bool from_file = false;
  py::dict judged;
};

py::dict StatsDict(const stage::ValidationStats& s) {
  return py::dict(py::arg("centres") = s.count, py::arg("mean_um") = s.mean_mm * 1e3, py::arg("rms_um") = s.rms_mm * 1e3,
                  py::arg("max_um") = s.max_mm * 1e3, py::arg("predicted_rms_um") = s.predicted_rms_mm * 1e3);
}

py::dict FrameFreeDict(const stage::FrameFreeStats& s) {
  return py::dict(py::arg("count") = s.count, py::arg("rms_um") = s.rms_mm * 1e3, py::arg("max_um") = s.max_mm * 1e3,
                  py::arg("predicted_rms_um") = s.predicted_rms_mm * 1e3);
}

py::dict JudgementDict(const workflows::Judgement& j) {
  py::dict d = StatsDict(j.first_tile);
  d["rigid"] = FrameFreeDict(j.rigid);
  d["distances"] = FrameFreeDict(j.distances);
  return d;
}

// The placements of a batch given as arrays: {name: {"ids": [...], "stitched": N x 3, "free": N x 3}}, paired and
// checked as the batch reader pairs two exports (same calottes in both).
artefacts::Batch BatchFromArrays(const py::dict& placements, const std::optional<std::vector<std::string>>& identify,
                                 const std::optional<std::vector<std::string>>& validate) {
  artefacts::Batch batch;
  batch.dir = "<arrays>";
  for (const auto& [key, value] : placements) {
    const std::string name = py::str(key);
    const py::dict p = value.cast<py::dict>();
    for (const char* k : {"ids", "stitched", "free"}) {
      if (!p.contains(k)) throw InputError(fmt::format("placement {}: no '{}' (give ids, stitched and free)", name, k));
    }
    const std::vector<int> ids = p["ids"].cast<std::vector<int>>();
    const auto exported = [&](const char* which) {
      const std::string source = name + "." + which;
      const std::vector<Eigen::Vector3d> points = PointsFrom(p[which].cast<DoubleArray>(), source);
      if (points.size() != ids.size()) {
        throw InputError(fmt::format("{}: {} centres for {} ids", source, points.size(), ids.size()));
      }
      artefacts::CentreExport e;
      e.source = source;
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (e.Find(ids[i]) != nullptr) throw InputError(fmt::format("{}: calotte {} appears twice", source, ids[i]));
        artefacts::CentreRecord r;
        r.id = ids[i];
        r.position = points[i];
        r.line = static_cast<int>(i) + 1;
        e.centres.push_back(r);
      }
      return e;
    };
    batch.placements.push_back(artefacts::PairCentreExports(name, exported("stitched"), exported("free")));
  }
  if (batch.placements.empty()) throw InputError("no placements: give {name: {ids, stitched, free}, ...}");
  std::sort(batch.placements.begin(), batch.placements.end(),
            [](const artefacts::Placement& a, const artefacts::Placement& b) { return a.name < b.name; });
  batch.has_roles = identify || validate;
  artefacts::AssignBatchRoles(batch, identify, validate.value_or(std::vector<std::string>{}), "arrays");
  return batch;
}

// The keywords every calibration takes, as the command line's options.
workflows::CalibrateJobOptions JobOptions(const py::object& model, const std::string& terms, const std::string& anchor,
                                          const std::string& loss, double loss_scale_um,
                                          const std::string& stitched_frame, int threads) {
  workflows::CalibrateJobOptions options;
  options.model.model = py::str(model);
  options.model.terms = terms;
  options.settings.anchor = anchor;
  options.settings.loss = loss;
  options.settings.loss_scale_um = loss_scale_um;
  options.settings.stitched_frame = stitched_frame;
  options.settings.threads = threads;
  return options;
}

void RefuseUnconverged(const stage::IdentificationResult& r, bool allow_unconverged) {
  if (!r.converged && !allow_unconverged) {
    throw NotConvergedError(fmt::format("model {}: the solver stopped after {} iterations without converging; do not "
                                        "use it: check the batch for outliers or try loss='huber' "
                                        "(allow_unconverged=True returns it anyway)",
                                        r.calibration.model, r.iterations));
  }
}

// The judged set's figures (the validation placements, or the identification ones without them), as the
// validation block names them, with what a plot of the correction needs: where each shown centre was commanded and
// its error before and after (stitched - compensated, the residual's opposite), in the first tile's frame.
py::dict JudgedDict(const workflows::BatchCalibrationRun& run) {
  const workflows::BatchCalibration& c = run.calibration;
  const workflows::BeforeAfter& judged = *c.judged;
  py::dict v = JudgementDict(judged.after);
  v["placements"] = c.validation ? run.input.batch.validate : run.input.batch.identify;
  v["held_out"] = c.validation.has_value();
  v["before"] = JudgementDict(judged.before);
  const auto max_abs = [](const std::vector<double>& e) {
    double m = 0;
    for (double x : e) m = std::max(m, std::abs(x));
    return m * 1e3;
  };
  v["distance_error_max_um"] = py::dict(py::arg("before") = max_abs(judged.distance_errors_before_mm),
                                        py::arg("after") = max_abs(judged.distance_errors_after_mm));
  const stage::MeasurementSet& shown = c.Shown();
  std::vector<Eigen::Vector3d> commands, before, after;
  for (std::size_t i = 0; i < shown.observations.size(); ++i) {
    commands.push_back(shown.observations[i].command);
    before.push_back(-judged.before.first_tile.residuals[i]);
    after.push_back(-judged.after.first_tile.residuals[i]);
  }
  v["commands"] = PointsArray(commands);
  v["errors_before"] = PointsArray(before);
  v["errors_after"] = PointsArray(after);
  return v;
}

PyCalibration Calibrate(const py::object& batch_arg, const py::object& model, const std::string& terms,
                        const std::string& anchor, const std::string& loss, double loss_scale_um,
                        const std::string& stitched_frame, int threads,
                        const std::optional<std::vector<std::string>>& identify,
                        const std::optional<std::vector<std::string>>& validate, bool allow_unconverged,
                        const std::string& artefact, const std::string& centres_dir) {
  workflows::CalibrateJobOptions options = JobOptions(model, terms, anchor, loss, loss_scale_um, stitched_frame, threads);
  options.artefact = artefact;
  options.centres_dir = centres_dir;
  options.judge_identification = true;  // what write_report and `judged` show without validation placements
  std::optional<workflows::CalibrationBatchInput> input;
  if (py::isinstance<py::dict>(batch_arg)) {
    input = workflows::CalibrationBatchInput{"arrays", BatchFromArrays(batch_arg.cast<py::dict>(), identify, validate), std::nullopt};
  } else {
    if (identify || validate) throw InputError("identify / validate go with a batch of arrays: a directory has batch.json");
    const std::string source = py::str(batch_arg);
    py::gil_scoped_release release;
    // Centre exports, or the instrument's raw surface exports (X3P, AL3D, SDF, TIFF) searched for the artefact's
    // calottes, as `fvm calibrate DIR --artefact NAME` does.
    input = workflows::ReadCalibrationBatch(source, options);
  }
  std::optional<workflows::BatchCalibrationRun> run;
  std::optional<workflows::Summary> summary;
  {
    py::gil_scoped_release release;
    run.emplace(workflows::CalibrateBatchInput(std::move(*input), options));
    summary.emplace(workflows::Summarize(*run));
  }
  RefuseUnconverged(run->calibration.result, allow_unconverged);
  return PyCalibration(std::move(*summary), run->calibration.result, false, JudgedDict(*run));
}

// distortion=None / False: none; True: identify the default order; N: identify order N (as --distortion [N]).
workflows::DistortionOptions DistortionKeywords(const py::object& distortion, const std::string& file, const std::string& save) {
  workflows::DistortionOptions d;
  d.file = file;
  d.save = save;
  if (!distortion.is_none() && !(py::isinstance<py::bool_>(distortion) && !distortion.cast<bool>())) {
    d.identify = true;
    if (!py::isinstance<py::bool_>(distortion)) d.order = py::str(distortion);
  }
  return d;
}

PyCalibration CalibrateScans(const std::vector<std::string>& scan, double pixel_mm, double pixel_u_mm,
                             const py::object& model, const std::string& terms, const std::string& anchor,
                             const std::string& loss, double loss_scale_um, const std::string& stitched_frame,
                             int threads, const std::string& validate, const py::object& distortion,
                             const std::string& distortion_file, const std::string& save_distortion,
                             bool allow_unconverged) {
  workflows::CalibrateJobOptions options = JobOptions(model, terms, anchor, loss, loss_scale_um, stitched_frame, threads);
  options.pixel_mm = pixel_mm;
  options.pixel_u_mm = pixel_u_mm;
  options.validate = validate;
  options.distortion = DistortionKeywords(distortion, distortion_file, save_distortion);
  if (scan.empty()) throw InputError("scan: give the layout CSV of at least one stitched calibration scan");
  std::optional<workflows::ScanCalibrationRun> run;
  std::optional<workflows::Summary> summary;
  {
    py::gil_scoped_release release;
    run.emplace(workflows::CalibrateScanLayouts(scan, options));
    summary.emplace(workflows::Summarize(*run));
  }
  RefuseUnconverged(run->calibration.fitted.result, allow_unconverged);
  return PyCalibration(std::move(*summary), run->calibration.fitted.result, false, py::dict());
}

}  // namespace

py::dict ParameterDict(const stage::IdentificationResult& result) {
  const nlohmann::json doc = stage::CalibrationToJson(result);
  std::vector<std::string> names, states, units;
  std::vector<double> values, u;
  for (const nlohmann::json& p : doc["parameters"]) {
    names.push_back(p["name"]);
    states.push_back(p["state"]);
    units.push_back(p["unit"]);
    values.push_back(p["value"]);
    u.push_back(p["u"]);
  }
  return py::dict(py::arg("names") = names, py::arg("values") = py::array_t<double>(py::cast(values)),
                  py::arg("u") = py::array_t<double>(py::cast(u)), py::arg("state") = states, py::arg("unit") = units);
}

std::vector<std::pair<std::string, std::string>> FixedCoefficients(const stage::IdentificationResult& result) {
  std::vector<std::pair<std::string, std::string>> fixed;
  for (const stage::FixedCoefficient& f : result.fixed) fixed.emplace_back(f.name, f.reason);
  return fixed;
}

void BindCalibrationJobs(py::module_& m);

void BindCalibration(py::module_& m) {
  py::class_<PyCalibration, workflows::Summary>(
      m, "Calibration",
      "An identified stage model: parameters (names, values, u in mm and rad), correct(points), save(path); an "
      "fvm.Result whose summary is `fvm calibrate --json`'s document (str(): the printed table; "
      "fvm.write_report(cal, dir): the --report files).\n\nExample:\n"
                            "    >>> cal = fvm.calibrate('samples/bar17', model=27)\n"
                            "    >>> p = cal.parameters\n    >>> dict(zip(p['names'], p['values']))['xTx1']")
      .def_property_readonly("model", [](const PyCalibration& c) { return c.result.calibration.model; })
      .def_property_readonly("chain", [](const PyCalibration& c) { return c.result.calibration.layout.chain().code; })
      .def_property_readonly("parameters", [](const PyCalibration& c) { return ParameterDict(c.result); },
                             "dict of names, values (numpy, mm and rad), u (standard uncertainties, k = 1), state "
                             "(free, fixed, tied) and unit, every coefficient in the order of the calibration file")
      .def_property_readonly("covariance", [](const PyCalibration& c) {
        const Eigen::MatrixXd& cov = c.result.calibration.covariance;
        py::array_t<double> out({cov.rows(), cov.cols()});
        for (Eigen::Index i = 0; i < cov.rows(); ++i) {
          for (Eigen::Index j = 0; j < cov.cols(); ++j) out.mutable_at(i, j) = cov(i, j);
        }
        return out;
      }, "covariance of the free coefficients (in the order of the free names of parameters)")
      .def_property_readonly("converged", [](const PyCalibration& c) { return c.result.converged || c.from_file; })
      .def_property_readonly("iterations", [](const PyCalibration& c) { return c.result.iterations; })
      .def_property_readonly("condition_number", [](const PyCalibration& c) { return c.result.condition_number; })
      .def_property_readonly("fixed", [](const PyCalibration& c) { return FixedCoefficients(c.result); },
                             "(name, reason) of the coefficients the data could not determine, fixed at 0")
      .def_readonly("judged", &PyCalibration::judged,
                    "the set that judged a batch calibration (its validation placements, or the identification "
                    "ones without them) as the --json validation block names it (rigid, distances, first tile "
                    "before and after, held_out), with commands and errors_before / errors_after, N x 3 mm, for "
                    "plots; empty for a scan calibration or a file")
      .def(
          "correct",
          [](const PyCalibration& c, const DoubleArray& points) {
            const std::vector<Eigen::Vector3d> p = PointsFrom(points, "points");
            std::vector<Eigen::Vector3d> corrected(p.size()), u(p.size());
            {
              py::gil_scoped_release release;
              for (std::size_t i = 0; i < p.size(); ++i) {
                const stage::CorrectedPoint q = stage::Correct(c.result.calibration, p[i]);
                corrected[i] = q.position;
                u[i] = q.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
              }
            }
            return py::make_tuple(PointsArray(corrected), PointsArray(u));
          },
          py::arg("points"),
          "Compensates stitching-free points (N x 3, mm) in the stage frame, as `fvm correct` does a centre "
          "export: returns (points, u), both N x 3 mm, u the standard uncertainties from the model's "
          "covariance.\n\nExample:\n    >>> corrected, u = cal.correct(np.array([[10.0, 5.0, 0.0]]))")
      .def(
          "save",
          [](const PyCalibration& c, const std::filesystem::path& path) {
            if (c.from_file) {
              throw InputError(path.string() + ": a calibration read from a file holds no fit to write again; copy the "
                               "file instead; nothing was written");
            }
            WriteFileAtomically(path, c.json.dump(2) + "\n");
          },
          py::arg("path"),
          "Writes the calibration file `fvm correct --calibration` reads (JSON, mm and rad), atomically: the file "
          "`fvm calibrate -o` writes for the same calibration (its summary).\n\n"
          "Example:\n    >>> cal.save('cal.json')")
      .def("to_json", [](const PyCalibration& c) { return c.json.dump(2); },
           "The calibration file's JSON text (parameters, covariance, residual statistics, what judged it).\n\nExample:\n"
           "    >>> import json; json.loads(cal.to_json())['parameters'][0]")
      .def("__repr__", [](const PyCalibration& c) {
        return fmt::format("<fvm.Calibration model {} ({} free parameters{})>", c.result.calibration.model,
                           c.result.calibration.layout.NumFree(), c.from_file ? ", from a file" : "");
      });

  BindCalibrationJobs(m);
}

// fvm.calibrate, fvm.calibrate_scans, fvm.read_calibration.
void BindCalibrationJobs(py::module_& m) {
  const workflows::CalibrateJobOptions defaults;  // the keywords' defaults are the command line's
  m.def("calibrate", &Calibrate, py::arg("batch"), py::arg("model") = defaults.model.model,
        py::arg("terms") = defaults.model.terms, py::arg("anchor") = defaults.settings.anchor,
        py::arg("loss") = defaults.settings.loss, py::arg("loss_scale_um") = defaults.settings.loss_scale_um,
        py::arg("stitched_frame") = defaults.settings.stitched_frame, py::arg("threads") = defaults.settings.threads,
        py::arg("identify") = std::nullopt, py::arg("validate") = std::nullopt, py::arg("allow_unconverged") = false,
        py::arg("artefact") = defaults.artefact, py::arg("centres_dir") = defaults.centres_dir,
        "Identifies the stage model (9, 15, 27 or 42 parameters, or `terms`) from a batch, as `fvm calibrate BATCH "
        "--model N` does: a batch directory (pairs <placement>.stitched.csv / .free.csv, optional batch.json; or "
        "the raw surface exports <placement>.stitched.x3p / .free.x3p etc., searched for the calottes of "
        "`artefact`, their centre exports written into `centres_dir` when given), or "
        "a dict {name: {'ids': [...], 'stitched': N x 3, 'free': N x 3}} with optional identify / validate lists "
        "of names. Returns a Calibration: its summary is `fvm calibrate --json`'s document, save() writes what -o "
        "writes, fvm.write_report(cal, dir) what --report writes. Raises fvm.InputError for a bad batch or a model "
        "it cannot carry, fvm.NotConvergedError when the solver did not converge (unless allow_unconverged)."
        "\n\nExample:\n"
        "    >>> cal = fvm.calibrate('samples/bar17', model=27)\n"
        "    >>> cal.summary['validation']['distances']['rms_um']");

  m.def("calibrate_scans", &CalibrateScans, py::arg("scan"), py::arg("pixel_mm"),
        py::arg("pixel_u_mm") = defaults.pixel_u_mm, py::arg("model") = defaults.model.model,
        py::arg("terms") = defaults.model.terms, py::arg("anchor") = defaults.settings.anchor,
        py::arg("loss") = defaults.settings.loss, py::arg("loss_scale_um") = defaults.settings.loss_scale_um,
        py::arg("stitched_frame") = defaults.settings.stitched_frame, py::arg("threads") = defaults.settings.threads,
        py::arg("validate") = defaults.validate, py::arg("distortion") = py::none(),
        py::arg("distortion_file") = defaults.distortion.file, py::arg("save_distortion") = defaults.distortion.save,
        py::arg("allow_unconverged") = false,
        "Identifies the stage model from stitched calibration scans of any textured part, as `fvm calibrate --scan "
        "L.csv [--scan ...] --pixel-mm P` does: `scan` the layout CSVs (file,row,col,x,y[,z], encoder readings in "
        "mm), `pixel_mm` the pixel size on the part and `pixel_u_mm` its standard uncertainty, `validate` an "
        "artefact batch whose validation placements judge the result (and make a report), `distortion` True or an "
        "order 2-6 to identify the objective's field distortion from the overlaps (or `distortion_file` a saved "
        "one; `save_distortion` writes it). Returns a Calibration whose summary is `fvm calibrate --scan ... "
        "--json`'s document.\n\nExample:\n"
        "    >>> cal = fvm.calibrate_scans(['s/row.csv', 's/column.csv', 's/diagonal.csv'], pixel_mm=0.022, model=15)\n"
        "    >>> cal.summary['predicted_xy_u_um']['combined']");

  m.def(
      "read_calibration",
      [](const std::filesystem::path& path) {
        stage::IdentificationResult result(stage::ReadCalibration(path));
        std::ifstream in(path);
        workflows::Summary summary{nlohmann::json::parse(in, nullptr, false), "", std::nullopt};
        return PyCalibration(std::move(summary), std::move(result), true, py::dict());
      },
      py::arg("path"),
      "Reads a calibration file written by `fvm calibrate -o` (or Calibration.save) for correct(); its summary "
      "is the file's document.\n\nExample:\n"
      "    >>> cal = fvm.read_calibration('cal.json')\n    >>> cal.correct(points)");
}

}  // namespace fvm::python

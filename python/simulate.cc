// fvm.simulate_batch and fvm.simulate_scan: synthetic data with a recorded truth written into a directory, as
// `fvm simulate fvm-batch` and `fvm simulate scan` write it (workflows/simulate_batch.h, workflows/simulate_scan.h).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>

#include "python/bindings.h"
#include "workflows/simulate_batch.h"
#include "workflows/simulate_scan.h"

namespace fvm::python {
namespace {

workflows::Summary SimulateBatch(const std::filesystem::path& output, unsigned seed, const std::string& truth_model,
                                 const std::string& truth_terms, double mean_error_um, double noise_um,
                                 int validation_placements, double pitch_error_um, const std::string& hidden_effect,
                                 double effect_size, double drift_tau_min, double periodic_um, double period_mm,
                                 double height_step_mm, bool serpentine, bool different_starts,
                                 const std::string& stitched_frame, const std::string& surfaces,
                                 double surface_pixel_mm, double surface_noise_um) {
  workflows::SimulateBatchOptions o;
  o.batch.seed = seed;
  o.batch.truth_model = truth_model;
  o.batch.truth_terms = truth_terms;
  o.batch.mean_error_um = mean_error_um;
  o.batch.noise_um = noise_um;
  o.batch.validation_placements = validation_placements;
  o.batch.pitch_error_um = pitch_error_um;
  o.batch.hidden_effect = hidden_effect;
  o.batch.effect_size = effect_size;
  o.batch.drift_tau_min = drift_tau_min;
  o.batch.periodic_um = periodic_um;
  o.batch.period_mm = period_mm;
  o.batch.height_step_mm = height_step_mm;
  o.batch.serpentine = serpentine;
  o.different_starts = different_starts;
  o.stitched_frame = stitched_frame;
  o.surfaces = surfaces;
  o.surface.pixel_mm = surface_pixel_mm;
  o.surface.noise_um = surface_noise_um;
  o.Check();
  py::gil_scoped_release release;
  return workflows::Summarize(workflows::SimulateBatch(o, output));
}

workflows::Summary SimulateScan(const std::filesystem::path& output, const std::optional<std::filesystem::path>& truth,
                                unsigned seed, const std::string& lens, int tile_px, const std::string& overlap,
                                double length_mm, const std::vector<double>& heights, const std::string& texture,
                                const std::string& tiles, std::optional<double> periodic_um, double period_mm,
                                int validation, double distortion) {
  workflows::SimulateScanOptions o;
  if (truth) o.calibration_truth = truth->string();
  o.seed = seed;
  o.lens = lens;
  o.tile_px = tile_px;
  o.overlap = overlap;
  o.length_mm = length_mm;
  o.heights_mm = heights;
  o.texture = texture;
  o.tiles = tiles;
  if (periodic_um) o.periodic_um = *periodic_um;
  o.period_mm = period_mm;
  o.validation = validation;
  o.distortion_px = distortion;
  o.Check();
  py::gil_scoped_release release;
  return workflows::Summarize(workflows::SimulateScans(o, output));
}

}  // namespace

void BindSimulate(py::module_& m) {
  const workflows::SimulateBatchOptions b;
  m.def("simulate_batch", &SimulateBatch, py::arg("output"), py::kw_only(), py::arg("seed") = b.batch.seed,
        py::arg("truth_model") = b.batch.truth_model, py::arg("truth_terms") = b.batch.truth_terms,
        py::arg("mean_error_um") = b.batch.mean_error_um, py::arg("noise_um") = b.batch.noise_um,
        py::arg("validation_placements") = b.batch.validation_placements,
        py::arg("pitch_error_um") = b.batch.pitch_error_um, py::arg("hidden_effect") = b.batch.hidden_effect,
        py::arg("effect_size") = b.batch.effect_size, py::arg("drift_tau_min") = b.batch.drift_tau_min,
        py::arg("periodic_um") = b.batch.periodic_um, py::arg("period_mm") = b.batch.period_mm,
        py::arg("height_step_mm") = b.batch.height_step_mm, py::arg("serpentine") = b.batch.serpentine,
        py::arg("different_starts") = b.different_starts, py::arg("stitched_frame") = b.stitched_frame,
        py::arg("surfaces") = b.surfaces, py::arg("surface_pixel_mm") = b.surface.pixel_mm,
        py::arg("surface_noise_um") = b.surface.noise_um,
        "Writes a synthetic calibration batch into `output`, as `fvm simulate fvm-batch -o OUTPUT` with the same "
        "options (keywords spelled as its options): 17-calotte bar placements, stitched and stitching-free, and "
        "truth.json. Returns an fvm.Result whose summary is the truth.json document.\n\nExample:\n"
        "    >>> r = fvm.simulate_batch('batch', seed=7)\n    >>> r['mean_error_um'], r['parameters'][0]");
  const workflows::SimulateScanOptions s;
  m.def("simulate_scan", &SimulateScan, py::arg("output"), py::kw_only(), py::arg("calibration_truth") = py::none(),
        py::arg("seed") = s.seed, py::arg("lens") = s.lens, py::arg("tile_px") = s.tile_px,
        py::arg("overlap") = s.overlap, py::arg("length_mm") = s.length_mm, py::arg("heights") = s.heights_mm,
        py::arg("texture") = s.texture, py::arg("tiles") = s.tiles, py::arg("periodic_um") = py::none(),
        py::arg("period_mm") = s.period_mm, py::arg("validation") = s.validation,
        py::arg("distortion") = s.distortion_px,
        "Writes stitched calibration scans of a textured part on a stage with known errors into `output`, as "
        "`fvm simulate scan -o OUTPUT` with the same options: tiles, layouts, truth.json and validation positions. "
        "heights: the encoder z of each set of paths (mm); periodic_um None: the truth file's, else 0.3. Returns an "
        "fvm.Result whose summary is the truth.json document, str() the lines the command prints.\n\nExample:\n"
        "    >>> r = fvm.simulate_scan('scans', seed=1, tile_px=256)\n    >>> r['pixel_mm'], r['scans']");
}

}  // namespace fvm::python

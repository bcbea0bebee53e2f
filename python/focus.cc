// Focus variation: a height map, its per-pixel uncertainty and the all-in-focus image from a stack of images at
// known z (`fvm focus`), the stack given as a 3-D array.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <fmt/core.h>

#include "core/input_error.h"
#include "imaging/focus_variation.h"
#include "python/bindings.h"
#include "workflows/focus.h"

namespace fvm::python {
namespace {

// The stack's pixels in the type the camera gave them (8- or 16-bit stay so: a deep stack stays small), anything
// else as float32.
struct StackPixels {
  py::array array;
  std::vector<imaging::StackImageView> views;
};

template <typename T>
StackPixels ViewsOf(const py::array& stack) {
  const auto typed = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(stack);
  if (!typed) throw InputError("stack: the images must hold numbers (uint8, uint16 or float)");
  StackPixels s{typed, {}};  // holds the converted pixels the views point into
  const int n = static_cast<int>(typed.shape(0)), h = static_cast<int>(typed.shape(1)), w = static_cast<int>(typed.shape(2));
  const std::size_t per_image = static_cast<std::size_t>(h) * static_cast<std::size_t>(w);
  for (int i = 0; i < n; ++i) {
    s.views.push_back({w, h, std::span<const T>(typed.data() + per_image * static_cast<std::size_t>(i), per_image), 1});
  }
  return s;
}

imaging::PeakFit ParsePeakFitName(const std::string& name) {
  if (name == "power") return imaging::PeakFit::kPower;
  if (name == "gaussian") return imaging::PeakFit::kGaussian;
  if (name == "parabolic") return imaging::PeakFit::kParabolic;
  throw InputError("peak_fit '" + name + "': use power, gaussian or parabolic");
}

// The arrays of a reconstruction and its summary (the document of `fvm focus --json`, less the path).
py::dict FocusDict(const workflows::FocusSummary& summary) {
  const imaging::FocusResult& r = summary.read.focus;
  const int h = r.height.size_y, w = r.height.size_x;
  py::dict out;
  out["heights"] = GridArray(summary.map.z_mm, h, w);
  out["u"] = GridArray(r.u_z_mm, h, w);
  out["quality"] = GridArray(r.quality, h, w);
  out["peak_index"] = GridArray(r.peak_index, h, w);
  py::array_t<double> image(r.texture_channels == 1 ? std::vector<py::ssize_t>{h, w} : std::vector<py::ssize_t>{h, w, r.texture_channels});
  std::copy(r.texture.begin(), r.texture.end(), image.mutable_data());
  out["image"] = image;
  out["spacing"] = std::make_pair(r.height.dx_mm, r.height.dy_mm);
  out["summary"] = ToPython(workflows::Summarize(summary, "").json);
  return out;
}

py::dict Focus(const py::array& stack, const std::vector<double>& z_mm, double dx_mm, double dy_mm,
               const std::string& measure, int window, bool adaptive_window, const std::string& peak_fit,
               double min_quality, bool keep_end_peaks) {
  if (stack.ndim() != 3) {
    throw InputError(fmt::format("stack: expected a 3-D array (images, rows, cols), got {} dimensions", stack.ndim()));
  }
  if (static_cast<std::size_t>(stack.shape(0)) != z_mm.size()) {
    throw InputError(fmt::format("stack: {} images for {} z positions", stack.shape(0), z_mm.size()));
  }
  imaging::FocusVariationOptions options;
  const std::optional<imaging::FocusMeasure> m = imaging::ParseFocusMeasure(measure);
  if (!m) throw InputError("measure '" + measure + "': use laplacian, tenengrad or variance");
  options.measure = *m;
  options.window = window;
  options.adaptive_window = adaptive_window;
  options.peak_fit = ParsePeakFitName(peak_fit);
  options.min_quality = min_quality;
  options.keep_end_peaks = keep_end_peaks;
  options.dx_mm = dx_mm;
  options.dy_mm = dy_mm;
  options.Check();
  const py::dtype type = stack.dtype();
  const StackPixels pixels = type.is(py::dtype::of<std::uint8_t>())    ? ViewsOf<std::uint8_t>(stack)
                             : type.is(py::dtype::of<std::uint16_t>()) ? ViewsOf<std::uint16_t>(stack)
                                                                       : ViewsOf<float>(stack);
  std::optional<imaging::FocusResult> r;
  {
    py::gil_scoped_release release;
    r.emplace(imaging::ReconstructFocusStack(pixels.views, z_mm, options));
  }
  workflows::FocusSummary summary;
  for (const double z : z_mm) summary.entries.push_back({"", z, 1, {}});  // z given: heights in mm
  summary.read.focus = std::move(*r);
  summary.variation = options;
  workflows::ComputeFocusFigures(summary);
  return FocusDict(summary);
}

workflows::FocusSummary FocusFiles(const std::vector<std::filesystem::path>& stack, const workflows::FocusOptions& options) {
  options.Check();
  py::gil_scoped_release release;
  return workflows::ReconstructFocus(imaging::ResolveFocusStack(stack, options.z_step_mm), options);
}

}  // namespace

void BindFocus(py::module_& m) {
  const workflows::FocusOptions d;
  m.def(
      "focus_files",
      [](const py::object& stack, std::optional<double> z_step_mm, bool align, bool keep_end_peaks,
         const std::string& measure, const std::string& fit, int window_px, double min_quality, double pixel_mm,
         bool colour) {
        std::vector<std::filesystem::path> inputs;
        if (py::isinstance<py::str>(stack) || py::hasattr(stack, "__fspath__")) {
          inputs.push_back(stack.cast<std::filesystem::path>());
        } else {
          inputs = stack.cast<std::vector<std::filesystem::path>>();
        }
        const workflows::FocusOptions options{z_step_mm, align, keep_end_peaks, measure, fit, window_px,
                                              min_quality, pixel_mm, colour, 0};
        return FocusDict(FocusFiles(inputs, options));
      },
      py::arg("stack"), py::kw_only(), py::arg("z_step_mm") = d.z_step_mm, py::arg("align") = d.align,
      py::arg("keep_end_peaks") = d.keep_end_peaks, py::arg("measure") = d.measure, py::arg("fit") = d.fit,
      py::arg("window_px") = d.window_px, py::arg("min_quality") = d.min_quality, py::arg("pixel_mm") = d.pixel_mm,
      py::arg("colour") = d.colour,
      "Focus variation of a stack of image files, as `fvm focus STACK` with the same options: STACK a CSV list "
      "'file,z_mm', a directory of images, or the image files in focus order (without a list, z is the index times "
      "z_step_mm, or the index itself). Returns the dict of fvm.focus (heights, u, quality, peak_index, image, "
      "spacing) with summary, the document of `fvm focus --json` less the path; colour: the all-in-focus image in "
      "colour when the images are.\n\nExample:\n    >>> r = fvm.focus_files('frames/', z_step_mm=0.002, align=True)\n"
      "    >>> r['heights'], r['summary']['valid_points']");

  m.def("focus", &Focus, py::arg("stack"), py::arg("z"), py::arg("dx_mm") = 0.001, py::arg("dy_mm") = 0.0,
        py::arg("measure") = "laplacian", py::arg("window") = 5, py::arg("adaptive_window") = true,
        py::arg("peak_fit") = "power", py::arg("min_quality") = 2.0, py::arg("keep_end_peaks") = false,
        "Focus variation, as `fvm focus` does for a stack of files: stack, a 3-D array (images, rows, cols) of "
        "grey images (uint8, uint16 or float), z the position of each image (mm, strictly monotonic), dx_mm the "
        "pixel size on the object. Returns a dict: heights (rows x cols mm, NaN where no clear focus peak), u (their "
        "standard uncertainties, mm), quality (peak over mean focus measure), peak_index, image (the all-in-focus "
        "image), spacing, summary (the figures `fvm focus --json` prints). Raises fvm.InputError for fewer than 3 images, unsorted z or a bad window.\n\nExample:\n"
        "    >>> r = fvm.focus(stack, z=np.arange(len(stack)) * 0.002, dx_mm=0.0011)\n"
        "    >>> r['heights'], r['u'], r['image']");
}

}  // namespace fvm::python

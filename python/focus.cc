// Focus variation: a height map, its per-pixel uncertainty and the all-in-focus image from a stack of images at
// known z (`fvm focus`), the stack given as a 3-D array.

#include <pybind11/stl.h>

#include <cstdint>
#include <fmt/core.h>

#include "core/input_error.h"
#include "imaging/focus_variation.h"
#include "python/bindings.h"

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
  const int h = r->height.size_y, w = r->height.size_x;
  py::dict out;
  out["heights"] = GridArray(r->height.z_mm, h, w);
  out["u"] = GridArray(r->u_z_mm, h, w);
  out["quality"] = GridArray(r->quality, h, w);
  out["peak_index"] = GridArray(r->peak_index, h, w);
  py::array_t<double> image(r->texture_channels == 1 ? std::vector<py::ssize_t>{h, w} : std::vector<py::ssize_t>{h, w, r->texture_channels});
  std::copy(r->texture.begin(), r->texture.end(), image.mutable_data());
  out["image"] = image;
  out["spacing"] = std::make_pair(r->height.dx_mm, r->height.dy_mm);
  return out;
}

}  // namespace

void BindFocus(py::module_& m) {
  m.def("focus", &Focus, py::arg("stack"), py::arg("z"), py::arg("dx_mm") = 0.001, py::arg("dy_mm") = 0.0,
        py::arg("measure") = "laplacian", py::arg("window") = 5, py::arg("adaptive_window") = true,
        py::arg("peak_fit") = "power", py::arg("min_quality") = 2.0, py::arg("keep_end_peaks") = false,
        "Focus variation, as `fvm focus` does for a stack of files: stack, a 3-D array (images, rows, cols) of "
        "grey images (uint8, uint16 or float), z the position of each image (mm, strictly monotonic), dx_mm the "
        "pixel size on the object. Returns a dict: heights (rows x cols mm, NaN where no clear focus peak), u (their "
        "standard uncertainties, mm), quality (peak over mean focus measure), peak_index, image (the all-in-focus "
        "image), spacing. Raises fvm.InputError for fewer than 3 images, unsorted z or a bad window.\n\nExample:\n"
        "    >>> r = fvm.focus(stack, z=np.arange(len(stack)) * 0.002, dx_mm=0.0011)\n"
        "    >>> r['heights'], r['u'], r['image']");
}

}  // namespace fvm::python

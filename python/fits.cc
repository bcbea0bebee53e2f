// Fits of a sphere or a plane to any point set (imaging/shape_fit.h: the orthogonal-distance elements of
// ISO 10360-6), with standard uncertainties from the residuals: `fvm fit FILE --shape sphere|plane`.

#include <pybind11/stl.h>

#include <fmt/core.h>
#include <stdexcept>

#include "core/input_error.h"
#include "imaging/shape_fit.h"
#include "python/bindings.h"

namespace fvm::python {
namespace {

imaging::ShapeFit Fit(const DoubleArray& points, imaging::Shape shape, bool robust, double outlier_sigmas,
                      std::uint64_t seed) {
  const std::vector<Eigen::Vector3d> p = PointsFrom(points, "points");
  imaging::ShapeFitOptions options;
  options.shape = shape;
  options.robust = robust;
  options.outlier_sigmas = outlier_sigmas;
  options.seed = seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  py::gil_scoped_release release;
  return imaging::FitShape(p, options);
}

constexpr const char* kFitOptionsDoc =
    " robust: find the shape among stray points (least median of squares with a fixed seed, then refits without "
    "the points beyond outlier_sigmas robust standard deviations).";

}  // namespace

void BindFits(py::module_& m) {
  py::class_<imaging::ShapeFit>(m, "ShapeFit",
                                "A fitted sphere (centre, radius, u_centre, u_radius) or plane (point, normal, "
                                "u_normal_rad), with rms (the orthogonal residuals' RMS, mm) and the inliers.\n\n"
                                "Example:\n    >>> f = fvm.fit_sphere(points)\n"
                                "    >>> f.centre, f.u_centre, f.radius, f.u_radius, f.rms")
      .def_property_readonly("shape", [](const imaging::ShapeFit& f) { return imaging::ShapeName(f.shape); })
      .def_property_readonly("centre", [](const imaging::ShapeFit& f) { return VectorArray(f.centre_mm); }, "mm")
      .def_readonly("radius", &imaging::ShapeFit::radius_mm, "mm")
      .def_property_readonly("u_centre", [](const imaging::ShapeFit& f) { return VectorArray(f.u_centre_mm); },
                             "standard uncertainties of the centre, mm")
      .def_readonly("u_radius", &imaging::ShapeFit::u_radius_mm, "standard uncertainty of the radius, mm")
      .def_property_readonly("point", [](const imaging::ShapeFit& f) { return VectorArray(f.point_mm); },
                             "the plane's point (centroid of the inliers), mm")
      .def_property_readonly("normal", [](const imaging::ShapeFit& f) { return VectorArray(f.normal); },
                             "the plane's unit normal (its largest component positive)")
      .def_readonly("u_normal_rad", &imaging::ShapeFit::u_normal_rad,
                    "standard uncertainty of the normal's direction about its least certain axis, rad")
      .def_readonly("rms", &imaging::ShapeFit::rms_mm, "RMS orthogonal distance of the inliers, mm")
      .def_readonly("points", &imaging::ShapeFit::points)
      .def_readonly("outliers", &imaging::ShapeFit::outliers)
      .def_property_readonly("inlier", [](const imaging::ShapeFit& f) {
        py::array_t<bool> out(static_cast<py::ssize_t>(f.inlier.size()));
        for (std::size_t i = 0; i < f.inlier.size(); ++i) out.mutable_at(static_cast<py::ssize_t>(i)) = f.inlier[i];
        return out;
      })
      .def_readonly("has_uncertainty", &imaging::ShapeFit::has_uncertainty,
                    "False when the points only just determine the shape (no residual to estimate noise from)")
      .def_readonly("method", &imaging::ShapeFit::method)
      .def("__repr__", [](const imaging::ShapeFit& f) {
        if (f.shape == imaging::Shape::kSphere) {
          return fmt::format("<fvm.ShapeFit sphere centre ({:.6f}, {:.6f}, {:.6f}) mm, radius {:.6f} +- {:.2g} mm, "
                             "rms {:.3g} um>", f.centre_mm.x(), f.centre_mm.y(), f.centre_mm.z(), f.radius_mm,
                             f.u_radius_mm, f.rms_mm * 1e3);
        }
        return fmt::format("<fvm.ShapeFit plane normal ({:.6f}, {:.6f}, {:.6f}), rms {:.3g} um>", f.normal.x(),
                           f.normal.y(), f.normal.z(), f.rms_mm * 1e3);
      });

  m.def(
      "fit_sphere",
      [](const DoubleArray& points, bool robust, double outlier_sigmas, std::uint64_t seed) {
        return Fit(points, imaging::Shape::kSphere, robust, outlier_sigmas, seed);
      },
      py::arg("points"), py::arg("robust") = false, py::arg("outlier_sigmas") = 3.0, py::arg("seed") = 1,
      (std::string("The orthogonal-distance least-squares sphere (ISO 10360-6) through an N x 3 array of points "
                   "(mm), with standard uncertainties from the residuals, as `fvm fit FILE --shape sphere`.") +
       kFitOptionsDoc +
       " Raises fvm.InputError for fewer than 4 points, coplanar points or a non-finite coordinate.\n\nExample:\n"
       "    >>> f = fvm.fit_sphere(points)\n    >>> f.centre, f.radius, f.u_radius")
          .c_str());

  m.def(
      "fit_plane",
      [](const DoubleArray& points, bool robust, double outlier_sigmas, std::uint64_t seed) {
        return Fit(points, imaging::Shape::kPlane, robust, outlier_sigmas, seed);
      },
      py::arg("points"), py::arg("robust") = false, py::arg("outlier_sigmas") = 3.0, py::arg("seed") = 1,
      (std::string("The orthogonal-distance least-squares plane through an N x 3 array of points (mm): its "
                   "centroid and unit normal, with the normal's standard uncertainty, as `fvm fit FILE --shape "
                   "plane`.") +
       kFitOptionsDoc +
       " Raises fvm.InputError for fewer than 3 points or collinear ones.\n\nExample:\n"
       "    >>> f = fvm.fit_plane(points)\n    >>> f.normal, f.u_normal_rad, f.rms")
          .c_str());
}

}  // namespace fvm::python

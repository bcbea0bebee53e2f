// Surfaces: a measurement file read into a height map or a point cloud (fvm info), a height map made from arrays,
// and the calottes found on one (fvm fit FILE).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <fmt/core.h>

#include "artefacts/geometry/artefact.h"
#include "core/input_error.h"
#include "imaging/io/surface_file.h"
#include "python/bindings.h"
#include "workflows/find_calottes.h"
#include "workflows/fit.h"
#include "workflows/surface_info.h"
#include "workflows/surface_read_options.h"

namespace fvm::python {
namespace {

using imaging::Surface;

// A height map from a 2-D array (rows along y), NaN where invalid; spacing one number (square pixels) or (dx, dy).
Surface SurfaceFromHeights(const DoubleArray& heights, const py::object& spacing, std::pair<double, double> origin) {
  if (heights.ndim() != 2) throw InputError(fmt::format("heights: expected a 2-D array, got {} dimensions", heights.ndim()));
  imaging::HeightMap map;
  map.size_y = static_cast<int>(heights.shape(0));
  map.size_x = static_cast<int>(heights.shape(1));
  try {
    if (py::isinstance<py::sequence>(spacing)) {
      std::tie(map.dx_mm, map.dy_mm) = spacing.cast<std::pair<double, double>>();
    } else {
      map.dx_mm = map.dy_mm = spacing.cast<double>();
    }
  } catch (const py::cast_error&) {
    throw InputError("spacing: give the pixel size in mm, one number or (dx, dy)");
  }
  if (!(map.dx_mm > 0 && map.dy_mm > 0 && std::isfinite(map.dx_mm) && std::isfinite(map.dy_mm))) {
    throw InputError(fmt::format("spacing: the pixel size must be positive and finite (mm), got {}, {}", map.dx_mm, map.dy_mm));
  }
  std::tie(map.x0_mm, map.y0_mm) = origin;
  map.z_mm.assign(heights.data(), heights.data() + heights.size());
  for (double& z : map.z_mm) {
    if (!std::isfinite(z)) z = NAN;  // inf is no height either
  }
  map.source = "numpy array";
  return {imaging::SurfaceFormat::kX3p, std::move(map), std::nullopt};
}

py::object HeightsOf(const Surface& s) {
  if (!s.height_map) return py::none();
  return GridArray(s.height_map->z_mm, s.height_map->size_y, s.height_map->size_x);
}

py::object MaskOf(const Surface& s) {
  if (!s.height_map) return py::none();
  const imaging::HeightMap& m = *s.height_map;
  py::array_t<bool> out({static_cast<py::ssize_t>(m.size_y), static_cast<py::ssize_t>(m.size_x)});
  bool* data = out.mutable_data();
  for (std::size_t i = 0; i < m.z_mm.size(); ++i) data[i] = std::isfinite(m.z_mm[i]);
  return out;
}

py::dict CalotteDict(const imaging::DetectedCalotte& c) {
  py::dict d;
  d["id"] = c.id;
  d["centre"] = VectorArray(c.fit.centre_mm);
  d["radius"] = c.fit.radius_mm;
  d["u_centre"] = VectorArray(c.fit.centre_covariance_mm2.diagonal().cwiseMax(0.0).cwiseSqrt());
  d["u_radius"] = c.fit.radius_sigma_mm;
  d["form_rms_um"] = c.fit.rms_deviation_mm * 1e3;
  d["points"] = c.fit.inliers;
  d["outliers"] = c.fit.points - c.fit.inliers;
  d["depth"] = c.depth_mm;
  d["converged"] = c.fit.converged;
  d["at_border"] = c.at_border;
  return d;
}

py::dict FoundDict(const workflows::FoundCalottes& found) {
  py::list calottes, rejected;
  for (const auto& c : found.detection.calottes) calottes.append(CalotteDict(c));
  for (const auto& r : found.detection.rejected) {
    py::dict d;
    d["centre"] = py::make_tuple(r.centre_mm.x(), r.centre_mm.y());
    d["reason"] = r.reason;
    rejected.append(d);
  }
  py::dict out;
  out["calottes"] = calottes;
  out["rejected"] = rejected;
  out["method"] = found.method;
  out["artefact"] = found.artefact ? py::object(py::str(found.artefact->name)) : py::object(py::none());
  const imaging::FacePlane& face = found.detection.face;
  out["face"] = py::dict(py::arg("slope_x") = face.b, py::arg("slope_y") = face.c, py::arg("sigma_um") = face.sigma_mm * 1e3);
  if (found.layout) {
    out["layout"] = py::dict(py::arg("rotation_deg") = found.layout->rotation_rad * 180.0 / M_PI,
                             py::arg("scale") = found.layout->scale, py::arg("rms_um") = found.layout->rms_mm * 1e3);
  } else {
    out["layout"] = py::none();
  }
  return out;
}

// The reading options of fvm info and fvm fit, as their keywords give them.
workflows::SurfaceReadOptions ReadOptions(double pixel_mm, double pixel_y_mm, double z_scale_mm, double z_offset_mm,
                                          std::optional<double> invalid, const std::string& unit) {
  return {pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm, invalid, unit};
}

constexpr const char* kReadDoc =
    " Reading keywords as the command's options: pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm, invalid (images), "
    "unit ('mm', 'um' or 'm': point clouds).";

void BindSurfaceJobs(py::module_& m) {
  const workflows::SurfaceReadOptions r;
  m.def(
      "info",
      [](const std::filesystem::path& path, double pixel_mm, double pixel_y_mm, double z_scale_mm, double z_offset_mm,
         std::optional<double> invalid, const std::string& unit) {
        const imaging::SurfaceReadOptions read =
            ReadOptions(pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm, invalid, unit).ToOptions();
        py::gil_scoped_release release;
        return workflows::Summarize(workflows::DescribeSurface(imaging::ReadSurface(path, read), path.string()),
                                    path.string());
      },
      py::arg("path"), py::kw_only(), py::arg("pixel_mm") = r.pixel_mm, py::arg("pixel_y_mm") = r.pixel_y_mm,
      py::arg("z_scale_mm") = r.z_scale_mm, py::arg("z_offset_mm") = r.z_offset_mm, py::arg("invalid") = r.invalid,
      py::arg("unit") = r.unit,
      (std::string("What a surface or point-cloud file holds, as `fvm info FILE`: an fvm.Result whose summary "
                   "equals `fvm info --json` less the path (size_x, size_y, dx_mm, dy_mm, valid_points, z_min_mm, "
                   "z_max_mm, format, ..., notes).") +
       kReadDoc + "\n\nExample:\n    >>> fvm.info('scan.x3p')['valid_points']")
          .c_str());
  const workflows::FitOptions f;
  m.def(
      "fit",
      [](const std::filesystem::path& path, std::optional<std::string> artefact, double radius_mm,
         std::optional<double> rotation_deg, double min_diameter_mm, double max_diameter_mm, double min_depth_mm,
         const std::string& residual, std::optional<std::string> shape, bool robust,
         std::optional<std::filesystem::path> output, double pixel_mm, double pixel_y_mm, double z_scale_mm,
         double z_offset_mm, std::optional<double> invalid, const std::string& unit) {
        workflows::FitOptions o{artefact.value_or(""), radius_mm, rotation_deg, min_diameter_mm, max_diameter_mm,
                                min_depth_mm, residual, shape.value_or(""), robust};
        o.Check(output.has_value());
        const imaging::SurfaceReadOptions read =
            ReadOptions(pixel_mm, pixel_y_mm, z_scale_mm, z_offset_mm, invalid, unit).ToOptions();
        py::gil_scoped_release release;
        const workflows::FitResult result = workflows::FitFile(path.string(), read, o);
        if (output) artefacts::WriteCentreExport(*output, workflows::FitCentreExport(result, output->string()));
        return workflows::Summarize(result);
      },
      py::arg("path"), py::kw_only(), py::arg("artefact") = py::none(), py::arg("radius_mm") = f.radius_mm,
      py::arg("rotation_deg") = f.rotation_deg, py::arg("min_diameter_mm") = f.min_diameter_mm,
      py::arg("max_diameter_mm") = f.max_diameter_mm, py::arg("min_depth_mm") = f.min_depth_mm,
      py::arg("residual") = f.residual, py::arg("shape") = py::none(), py::arg("robust") = f.robust,
      py::arg("output") = py::none(), py::arg("pixel_mm") = r.pixel_mm, py::arg("pixel_y_mm") = r.pixel_y_mm,
      py::arg("z_scale_mm") = r.z_scale_mm, py::arg("z_offset_mm") = r.z_offset_mm, py::arg("invalid") = r.invalid,
      py::arg("unit") = r.unit,
      (std::string("Finds the calottes in a file and fits a sphere to each, or with shape='sphere'|'plane' one "
                   "shape to every point, as `fvm fit FILE` with the same options; output writes the centre export "
                   "(CSV) as -o does. Returns an fvm.Result whose summary equals `fvm fit --json` less the paths.") +
       kReadDoc + "\n\nExample:\n    >>> r = fvm.fit('bar.x3p', artefact='bar17', output='bar.csv')\n"
                  "    >>> [c['id'] for c in r['calottes']]\n    >>> fvm.fit('sph1.ds', shape='sphere')['radius_mm']")
          .c_str());
}

}  // namespace

void BindSurfaces(py::module_& m) {
  BindSurfaceJobs(m);
  py::class_<Surface>(m, "Surface",
                      "A measured surface: a height map on a regular grid (heights, mask, spacing) or a point cloud "
                      "(points).\n\nExample:\n    >>> import numpy as np\n"
                      "    >>> s = fvm.Surface(np.zeros((100, 120)), spacing=0.002)\n"
                      "    >>> s.heights.shape, s.spacing\n    ((100, 120), (0.002, 0.002))")
      .def(py::init([](const DoubleArray& heights, const py::object& spacing, std::pair<double, double> origin) {
             return SurfaceFromHeights(heights, spacing, origin);
           }),
           py::arg("heights"), py::arg("spacing"), py::arg("origin") = std::make_pair(0.0, 0.0),
           "A height map from a 2-D array of heights in mm (row iy at y0 + iy dy), NaN where there is no point; "
           "spacing: the pixel size in mm, one number or (dx, dy); origin: (x0, y0) of point (0, 0), mm.")
      .def_static(
          "from_points",
          [](const DoubleArray& points) {
            return Surface{imaging::SurfaceFormat::kXyz, std::nullopt,
                           imaging::MakeUnorganisedCloud(PointsFrom(points, "points"))};
          },
          py::arg("points"),
          "An unorganised point cloud from an N x 3 array (mm).\n\nExample:\n"
          "    >>> s = fvm.Surface.from_points(np.random.default_rng(1).random((500, 3)))")
      .def_property_readonly("format", [](const Surface& s) { return imaging::FormatName(s.format); },
                             "the file format read: x3p, al3d, sdf, plu, plux, metropro, opd, sur, nms, tmd, image, pcd, ply, "
                             "xyz")
      .def_property_readonly("is_cloud", [](const Surface& s) { return s.cloud.has_value(); })
      .def_property_readonly("heights", &HeightsOf, "rows x cols float64 heights, mm, NaN where invalid (None for a cloud)")
      .def_property_readonly("mask", &MaskOf, "rows x cols bool, True where a height is valid (None for a cloud)")
      .def_property_readonly(
          "spacing", [](const Surface& s) { return s.height_map ? py::cast(std::make_pair(s.height_map->dx_mm, s.height_map->dy_mm)) : py::none(); },
          "(dx, dy), the pixel size in mm (None for a cloud)")
      .def_property_readonly(
          "origin", [](const Surface& s) { return s.height_map ? py::cast(std::make_pair(s.height_map->x0_mm, s.height_map->y0_mm)) : py::none(); },
          "(x0, y0) of point (0, 0), mm (None for a cloud)")
      .def_property_readonly(
          "points",
          [](const Surface& s) -> py::object {
            if (s.cloud) return PointsArray(s.cloud->points);
            return PointsArray(imaging::HeightMapToCloud(*s.height_map).points);
          },
          "N x 3 points, mm: the cloud's, or every grid point of a height map (NaN z where invalid)")
      .def_property_readonly("source", [](const Surface& s) { return s.height_map ? s.height_map->source : s.cloud->source; },
                             "what the reader found about the origin (format, instrument, date)")
      .def_property_readonly(
          "intensity",
          [](const Surface& s) -> py::object {
            if (!s.height_map || s.height_map->intensity.size() != s.height_map->z_mm.size()) return py::none();
            const imaging::HeightMap& h = *s.height_map;
            const std::vector<double> grey(h.intensity.begin(), h.intensity.end());
            return GridArray(grey, h.size_y, h.size_x);
          },
          "rows x cols float64 intensity (grey-level) image the instrument recorded with the heights, in its own "
          "units, NaN where it has none (None when the file holds none)")
      .def_property_readonly(
          "notes", [](const Surface& s) { return s.height_map ? s.height_map->notes : std::vector<std::string>{}; },
          "what the reader found unusual about the file and read anyway (an X3P zipped around its folder, ...)")
      .def_property_readonly(
          "summary", [](const Surface& s) { return ToPython(workflows::Summarize(workflows::DescribeSurface(s, "surface"), "surface").json); },
          "What the surface holds, as `fvm info --json` tells it of a file (less the path)")
      .def("__repr__", [](const Surface& s) {
        if (s.cloud) return fmt::format("<fvm.Surface cloud of {} points>", s.cloud->points.size());
        const imaging::HeightMap& h = *s.height_map;
        return fmt::format("<fvm.Surface {} x {} heights, spacing {} x {} mm>", h.size_y, h.size_x, h.dx_mm, h.dy_mm);
      });

  m.def(
      "read_surface",
      [](const std::filesystem::path& path, double dx_mm, double dy_mm, double z_scale_mm, double z_offset_mm,
         std::optional<double> invalid_value, double mm_per_unit) {
        imaging::SurfaceReadOptions options;
        options.image = {dx_mm, dy_mm, z_scale_mm, z_offset_mm, invalid_value};
        options.cloud.mm_per_unit = mm_per_unit;
        options.Check();
        return imaging::ReadSurface(path, options);
      },
      py::arg("path"), py::arg("dx_mm") = 0.0, py::arg("dy_mm") = 0.0, py::arg("z_scale_mm") = 0.0,
      py::arg("z_offset_mm") = 0.0, py::arg("invalid_value") = std::nullopt, py::arg("mm_per_unit") = 1.0,
      py::call_guard<py::gil_scoped_release>(),
      "Reads any surface or point-cloud file fvm reads (X3P, AL3D, SDF, TIFF/EXR/PNG height images, PCD, PLY, "
      "XYZ), as `fvm info` does. Images need their pixel size (dx_mm) unless the file holds it; integer images "
      "their z scale. Raises fvm.InputError naming the file.\n\nExample:\n"
      "    >>> s = fvm.read_surface('scan.x3p')\n    >>> s.heights.shape, s.spacing, s.mask.mean()");

  m.def(
      "write_surface",
      [](const std::filesystem::path& path, const Surface& surface) {
        if (!surface.height_map) throw InputError(path.string() + ": a point cloud is not a height map; nothing was written");
        imaging::WriteHeightMap(path, *surface.height_map);
      },
      py::arg("path"), py::arg("surface"), py::call_guard<py::gil_scoped_release>(),
      "Writes a height map by the extension (.x3p float64, .al3d, .tif/.exr float32), atomically.\n\nExample:\n"
      "    >>> fvm.write_surface('out.x3p', fvm.Surface(z, spacing=0.002))");

  m.def(
      "find_calottes",
      [](const Surface& surface, std::optional<std::string> artefact, double radius_mm,
         std::optional<double> rotation_deg, double min_diameter_mm, double max_diameter_mm, double min_depth_mm,
         const std::string& residual, const std::string& name) {
        Surface copy = surface;  // the workflow takes its surface
        workflows::FitResult result{name, {artefact.value_or(""), radius_mm, rotation_deg, min_diameter_mm,
                                           max_diameter_mm, min_depth_mm, residual, "", false}, {}, {}};
        result.options.Check();
        const workflows::FindCalottesOptions options = result.options.CalotteSearch();
        {
          py::gil_scoped_release release;
          result.found = workflows::FindCalottes(std::move(copy), options, name);
        }
        py::dict out = FoundDict(*result.found);
        out["summary"] = ToPython(workflows::Summarize(result).json);
        return out;
      },
      py::arg("surface"), py::arg("artefact") = std::nullopt, py::arg("radius_mm") = 0.0,
      py::arg("rotation_deg") = std::nullopt, py::arg("min_diameter_mm") = 0.0, py::arg("max_diameter_mm") = 0.0,
      py::arg("min_depth_mm") = 0.0, py::arg("residual") = "height", py::arg("name") = "surface",
      "Finds the calottes (spherical dimples) on a surface and fits a sphere to each, as `fvm fit FILE` does; with "
      "an artefact name (bar17, grid6x6, ...) numbers them by its layout. Returns a dict: calottes (id, centre, "
      "radius, u_centre, form_rms_um, points, ...), rejected, method, face, layout, and summary (the document of "
      "`fvm fit --json` less the path). `name` prefixes every refusal.\n\nExample:\n    >>> found = fvm.find_calottes(fvm.read_surface('bar.x3p'), artefact='bar17')\n"
      "    >>> [c['centre'] for c in found['calottes']]");
}

}  // namespace fvm::python

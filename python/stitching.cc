// Stitching: overlapping tiles registered into one frame (`fvm stitch --layout L.csv --overlap PCT`), the tiles
// given as arrays (grey or colour), as image files, or as the layout file the command reads.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/core.h>

#include <cmath>

#include "core/input_error.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_plan.h"
#include "python/bindings.h"
#include "workflows/field_distortion_file.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"

namespace fvm::python {
namespace {

// What fvm.stitch returns: the summary (`.summary`, the command's --json document; str(), its text) and the arrays
// (`["positions"]`, ...).
struct Stitched : workflows::Summary {
  py::dict values;
};

bool IsPath(const py::handle& object) {
  return py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__");
}

// A tile as fvm stitch reads one: a 2-D grey image, or H x W x C colour averaged to grey as the command averages a
// colour file (imaging/io/tile_image.h: C = 2 or 4 carries alpha last, which is left out); or an image file's path.
imaging::TileImage TileFrom(const py::handle& tile, std::size_t index) {
  if (IsPath(tile)) return imaging::ReadTileImage(py::cast<std::filesystem::path>(tile));
  using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
  const FloatArray a = py::cast<FloatArray>(tile);
  if (a.ndim() != 2 && a.ndim() != 3) {
    throw InputError(fmt::format("tile {}: expected a 2-D grey or an H x W x C colour image, got {} dimensions", index,
                                 a.ndim()));
  }
  const py::ssize_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  if (channels < 1 || channels > 4) {
    throw InputError(fmt::format("tile {}: {} channels; give grey, grey and alpha, RGB or RGBA", index, channels));
  }
  const py::ssize_t grey = channels == 2 || channels == 4 ? channels - 1 : channels;
  imaging::TileImage image(a.shape(0), a.shape(1));
  const float* p = a.data();
  for (Eigen::Index i = 0; i < image.size(); ++i, p += channels) {
    double sum = 0.0;
    for (py::ssize_t c = 0; c < grey; ++c) sum += p[c];
    image.data()[i] = static_cast<float>(sum / static_cast<double>(grey));
  }
  return image;
}

// The tiles and their layout from arrays (or image paths) and (row, col) pairs, as a layout file would give them.
workflows::LayoutTiles TilesFrom(const py::sequence& tiles, const std::vector<std::pair<int, int>>& layout,
                                 const std::optional<std::vector<std::pair<double, double>>>& stage_mm) {
  if (tiles.size() != layout.size()) {
    throw InputError(fmt::format("{} tiles for {} layout entries (row, col): give one per tile", tiles.size(), layout.size()));
  }
  if (stage_mm && stage_mm->size() != layout.size()) {
    throw InputError(fmt::format("stage_mm: {} positions for {} tiles", stage_mm->size(), layout.size()));
  }
  workflows::LayoutTiles t;
  t.layout.source = "layout";
  for (std::size_t i = 0; i < layout.size(); ++i) {
    imaging::TileLayoutEntry e;
    e.file = fmt::format("tile {}", i);
    std::tie(e.row, e.col) = layout[i];
    if (stage_mm) e.stage_mm = Eigen::Vector2d((*stage_mm)[i].first, (*stage_mm)[i].second);
    e.line = static_cast<int>(i) + 1;
    t.layout.rows = std::max(t.layout.rows, e.row + 1);
    t.layout.cols = std::max(t.layout.cols, e.col + 1);
    t.layout.tiles.push_back(e);
    t.images.push_back(TileFrom(tiles[i], i));
    if (t.images[i].rows() != t.images[0].rows() || t.images[i].cols() != t.images[0].cols()) {
      throw InputError(fmt::format("tile {} is {} x {} px, tile 0 {} x {}: one camera makes every tile", i,
                                   t.images[i].rows(), t.images[i].cols(), t.images[0].rows(), t.images[0].cols()));
    }
  }
  if (t.layout.tiles.empty()) throw InputError("no tiles");
  imaging::CheckLayoutForStitching(t.layout);
  return t;
}

// distortion: an order (True: 3), distortion_file: a field saved by --save-distortion (positions only).
std::optional<workflows::StitchDistortionOptions> DistortionFrom(const py::object& distortion,
                                                                  const std::optional<std::filesystem::path>& file) {
  const bool identify = !distortion.is_none() && !(py::isinstance<py::bool_>(distortion) && !distortion.cast<bool>());
  if (identify && file) throw InputError("distortion and distortion_file: give one (identify a field, or use a saved one)");
  if (!identify && !file) return std::nullopt;
  workflows::StitchDistortionOptions options;
  if (file) {
    options.known = workflows::ReadFieldDistortion(*file);
    if (options.known->Identity()) {
      throw InputError(file->string() + ": the field has no terms (order 0): leave out distortion_file to stitch rigidly");
    }
    return options;
  }
  options.order = py::isinstance<py::bool_>(distortion) ? 3 : distortion.cast<int>();
  if (options.order < 2 || options.order > imaging::kMaxDistortionOrder) {
    throw InputError(fmt::format("distortion {}: give the polynomial order 2..{} (3 by default)", options.order,
                                 imaging::kMaxDistortionOrder));
  }
  return options;
}

py::array_t<double> XyArray(const std::vector<Eigen::Vector2d>& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{2}});
  for (std::size_t i = 0; i < v.size(); ++i) {
    out.mutable_at(static_cast<py::ssize_t>(i), 0) = v[i].x();
    out.mutable_at(static_cast<py::ssize_t>(i), 1) = v[i].y();
  }
  return out;
}

py::dict Values(const workflows::StitchedLayout& s, const std::optional<imaging::Mosaic>& mosaic) {
  const workflows::StitchResult& r = s.Registered();
  const imaging::TilePositions& p = r.registration.positions;
  std::vector<Eigen::Vector2d> nominal;
  for (const imaging::GridTile& t : r.grid) nominal.push_back(t.nominal_px);
  py::list pairs;
  for (const imaging::PairRegistration& pr : r.registration.pairs) {
    pairs.append(py::dict(py::arg("a") = pr.a, py::arg("b") = pr.b, py::arg("accepted") = pr.accepted,
                          py::arg("offset") = py::make_tuple(pr.offset_px.x(), pr.offset_px.y()),
                          py::arg("quality") = pr.quality, py::arg("ambiguous") = pr.ambiguous,
                          py::arg("rejection") = pr.rejection));
  }
  py::dict out;
  out["positions"] = XyArray(s.PositionsPx());
  out["sigma"] = XyArray(s.SigmaPx());
  out["nominal"] = XyArray(nominal);
  out["registered"] = std::vector<bool>(p.registered.begin(), p.registered.end());
  out["pairs"] = pairs;
  out["accepted"] = r.accepted;
  out["ambiguous"] = r.ambiguous;
  out["mean_overlap_ncc"] = r.mean_overlap_ncc;
  out["from_stage"] = r.from_stage;
  out["at_stage_position"] = r.at_stage_position;
  out["without_neighbour"] = r.without_neighbour;
  out["overruled"] = r.overruled;
  out["pairs_unresolved"] = r.unresolved;
  out["unresolved_warning"] = r.UnresolvedWarning();
  if (mosaic) {
    out["mosaic"] = GridArray(std::vector<float>(mosaic->image.data(), mosaic->image.data() + mosaic->image.size()),
                              static_cast<int>(mosaic->image.rows()), static_cast<int>(mosaic->image.cols()));
    out["mosaic_origin_px"] = py::make_tuple(mosaic->origin_px.x(), mosaic->origin_px.y());
  }
  return out;
}

Stitched Stitch(const py::object& tiles, const std::optional<std::vector<std::pair<int, int>>>& layout,
                const std::optional<std::vector<std::pair<double, double>>>& stage_mm, double overlap, double pixel_mm,
                double min_quality, double stage_sigma_px, double search_fraction, const py::object& distortion,
                const std::optional<std::filesystem::path>& distortion_file, bool mosaic, int threads) {
  workflows::StitchLayoutOptions options;
  options.stitch.overlap = overlap >= 1.0 ? overlap / 100.0 : overlap;  // as --overlap reads 20 and 0.2
  options.stitch.pixel_mm = pixel_mm;
  options.stitch.registration.min_quality = min_quality;
  options.stitch.registration.stage_sigma_px = stage_sigma_px;
  options.stitch.registration.search_fraction = search_fraction;
  options.stitch.threads = threads;
  options.Check();
  options.distortion = DistortionFrom(distortion, distortion_file);
  workflows::LayoutTiles t;
  if (IsPath(tiles)) {
    if (layout || stage_mm) throw InputError("a layout file gives the tiles' rows, columns and stage positions: leave out layout and stage_mm");
    const auto path = py::cast<std::filesystem::path>(tiles);
    py::gil_scoped_release release;
    t = workflows::ReadLayoutTiles(path, 0, options.stitch.overlap);
  } else {
    if (!layout) throw InputError("layout: give the (row, col) of each tile (or the path of a layout file as tiles)");
    t = TilesFrom(py::cast<py::sequence>(tiles), *layout, stage_mm);
  }
  std::optional<workflows::StitchedLayout> s;
  std::optional<imaging::Mosaic> fused;
  {
    py::gil_scoped_release release;
    s.emplace(workflows::StitchLayout(t.layout, t.images, options));
    if (mosaic) fused = workflows::FuseStitched(*s, t.images);
  }
  Stitched out;
  static_cast<workflows::Summary&>(out) = workflows::Summarize(*s);
  out.values = Values(*s, fused);
  return out;
}

}  // namespace

void BindStitching(py::module_& m) {
  py::class_<Stitched, workflows::Summary>(
      m, "Stitched",
      "What fvm.stitch found: `summary` (the --json document of `fvm stitch`), str() its printed text, and the "
      "arrays by key: positions, sigma, nominal, registered, pairs, accepted, ... (keys of the summary too).")
      .def("__getitem__",
           [](const Stitched& s, const std::string& key) -> py::object {
             if (s.values.contains(key)) return s.values[py::str(key)];
             if (s.json.contains(key)) return ToPython(s.json.at(key));
             throw py::key_error(key);
           })
      .def("__contains__", [](const Stitched& s, const std::string& key) { return s.values.contains(key) || s.json.contains(key); })
      .def("keys", [](const Stitched& s) {
        std::vector<std::string> keys;
        for (const auto& item : s.values) keys.push_back(py::cast<std::string>(item.first));
        return keys;
      });
  const workflows::StitchOptions defaults;
  m.def("stitch", &Stitch, py::arg("tiles"), py::arg("layout") = std::nullopt, py::arg("stage_mm") = std::nullopt,
        py::arg("overlap") = defaults.overlap, py::arg("pixel_mm") = defaults.pixel_mm,
        py::arg("min_quality") = defaults.registration.min_quality,
        py::arg("stage_sigma_px") = defaults.registration.stage_sigma_px,
        py::arg("search_fraction") = defaults.registration.search_fraction, py::arg("distortion") = py::none(),
        py::arg("distortion_file") = std::nullopt, py::arg("mosaic") = false, py::arg("threads") = defaults.threads,
        "Registers overlapping tiles into one frame, as `fvm stitch --layout L.csv --overlap PCT` does. tiles: "
        "2-D grey images of one size (any numeric dtype; NaN marks invalid pixels), H x W x C colour images (the "
        "channels' mean, alpha left out, as the command reads a colour file) or image paths; or the path of a "
        "layout CSV (file,row,col[,x,y]) or of a Fiji tile configuration (TileConfiguration.txt, its rows and columns "
        "clustered with the tile size times 1 - overlap, its positions the nominal ones) as the command reads it. layout: (row, col) of each tile, row 0 the "
        "highest Y, in scan order (the first tile anchors the frame); stage_mm: optional (x, y) stage positions of "
        "the tiles' centres, used with pixel_mm for the nominal positions. overlap: a fraction (0.2) or percent "
        "(20). distortion: identify the objective's field distortion of this order (True: 3); distortion_file: a "
        "field saved by `fvm stitch --save-distortion`. mosaic: also fuse the tiles (result['mosaic']). Returns "
        "fvm.Stitched: .summary is the command's --json document, str() its text; by key: positions (N x 2 px of "
        "each tile's top-left, x right and y down from the first tile; the undistorted tiles' with a field), "
        "sigma (their standard uncertainties), nominal, registered, pairs, accepted, mean_overlap_ncc, overruled, "
        "pairs_unresolved, unresolved_warning. Raises fvm.InputError for an incomplete grid or tiles of different "
        "sizes.\n\nExample:\n"
        "    >>> r = fvm.stitch([t00, t01, t10, t11], [(0, 0), (0, 1), (1, 0), (1, 1)], overlap=0.25)\n"
        "    >>> r['positions'], r.summary['pairs_accepted']");
}

}  // namespace fvm::python

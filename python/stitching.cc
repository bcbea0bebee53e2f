// Stitching: overlapping tiles registered into one frame (`fvm stitch --layout L.csv --overlap PCT`), the tiles
// and the layout given as arrays.

#include <pybind11/stl.h>

#include <fmt/core.h>

#include "core/input_error.h"
#include "imaging/io/tile_layout.h"
#include "python/bindings.h"
#include "workflows/stitch.h"

namespace fvm::python {
namespace {

imaging::TileImage TileFrom(const py::handle& tile, std::size_t index) {
  using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
  const FloatArray a = py::cast<FloatArray>(tile);
  if (a.ndim() != 2) throw InputError(fmt::format("tile {}: expected a 2-D grey image, got {} dimensions", index, a.ndim()));
  imaging::TileImage image(a.shape(0), a.shape(1));
  std::copy(a.data(), a.data() + a.size(), image.data());
  return image;
}

py::dict Stitch(const py::sequence& tiles, const std::vector<std::pair<int, int>>& layout,
                const std::optional<std::vector<std::pair<double, double>>>& stage_mm, double overlap, double pixel_mm,
                double min_quality, double search_fraction, int threads) {
  if (tiles.size() != layout.size()) {
    throw InputError(fmt::format("{} tiles for {} layout entries (row, col): give one per tile", tiles.size(), layout.size()));
  }
  if (stage_mm && stage_mm->size() != layout.size()) {
    throw InputError(fmt::format("stage_mm: {} positions for {} tiles", stage_mm->size(), layout.size()));
  }
  imaging::TileLayout l;
  l.source = "layout";
  std::vector<imaging::TileImage> images;
  for (std::size_t i = 0; i < layout.size(); ++i) {
    imaging::TileLayoutEntry e;
    e.file = fmt::format("tile {}", i);
    std::tie(e.row, e.col) = layout[i];
    if (stage_mm) e.stage_mm = Eigen::Vector2d((*stage_mm)[i].first, (*stage_mm)[i].second);
    e.line = static_cast<int>(i) + 1;
    l.rows = std::max(l.rows, e.row + 1);
    l.cols = std::max(l.cols, e.col + 1);
    l.tiles.push_back(e);
    images.push_back(TileFrom(tiles[i], i));
    if (images[i].rows() != images[0].rows() || images[i].cols() != images[0].cols()) {
      throw InputError(fmt::format("tile {} is {} x {} px, tile 0 {} x {}: one camera makes every tile", i,
                                   images[i].rows(), images[i].cols(), images[0].rows(), images[0].cols()));
    }
  }
  if (l.tiles.empty()) throw InputError("no tiles");
  workflows::StitchOptions options;
  options.overlap = overlap;
  options.pixel_mm = pixel_mm;
  options.registration.min_quality = min_quality;
  options.registration.search_fraction = search_fraction;
  options.threads = threads;
  std::optional<workflows::StitchResult> r;
  {
    py::gil_scoped_release release;
    imaging::CheckLayoutComplete(l);
    r.emplace(workflows::StitchTiles(l, images, options));
  }
  const imaging::TilePositions& p = r->registration.positions;
  const auto xy = [](const std::vector<Eigen::Vector2d>& v) {
    py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{2}});
    for (std::size_t i = 0; i < v.size(); ++i) {
      out.mutable_at(static_cast<py::ssize_t>(i), 0) = v[i].x();
      out.mutable_at(static_cast<py::ssize_t>(i), 1) = v[i].y();
    }
    return out;
  };
  std::vector<Eigen::Vector2d> nominal;
  for (const imaging::GridTile& t : r->grid) nominal.push_back(t.nominal_px);
  py::list pairs;
  for (const imaging::PairRegistration& pr : r->registration.pairs) {
    pairs.append(py::dict(py::arg("a") = pr.a, py::arg("b") = pr.b, py::arg("accepted") = pr.accepted,
                          py::arg("offset") = py::make_tuple(pr.offset_px.x(), pr.offset_px.y()),
                          py::arg("quality") = pr.quality, py::arg("ambiguous") = pr.ambiguous,
                          py::arg("rejection") = pr.rejection));
  }
  py::dict out;
  out["positions"] = xy(p.positions_px);
  out["sigma"] = xy(p.sigma_px);
  out["nominal"] = xy(nominal);
  out["registered"] = std::vector<bool>(p.registered.begin(), p.registered.end());
  out["pairs"] = pairs;
  out["accepted"] = r->accepted;
  out["ambiguous"] = r->ambiguous;
  out["mean_overlap_ncc"] = r->mean_overlap_ncc;
  out["from_stage"] = r->from_stage;
  out["at_stage_position"] = r->at_stage_position;
  out["overruled"] = r->overruled;
  out["pairs_unresolved"] = r->unresolved;
  out["unresolved_warning"] = r->UnresolvedWarning();
  return out;
}

}  // namespace

void BindStitching(py::module_& m) {
  m.def("stitch", &Stitch, py::arg("tiles"), py::arg("layout"), py::arg("stage_mm") = std::nullopt,
        py::arg("overlap") = 0.2, py::arg("pixel_mm") = 0.0, py::arg("min_quality") = 0.5,
        py::arg("search_fraction") = 0.1, py::arg("threads") = 0,
        "Registers overlapping tiles into one frame, as `fvm stitch --layout L.csv --overlap PCT` does. tiles: "
        "2-D grey images of one size (any numeric dtype; NaN marks invalid pixels); layout: (row, col) of each "
        "tile, row 0 the highest Y, in scan order (the first tile anchors the frame); stage_mm: optional (x, y) "
        "stage positions of the tiles' centres, used with pixel_mm for the nominal positions. Returns a dict: "
        "positions (N x 2 px of each tile's top-left, x right and y down from the first tile), sigma (their "
        "standard uncertainties), nominal, registered, pairs, accepted, mean_overlap_ncc, overruled (the pairs the "
        "grid's loops contradicted, as text), pairs_unresolved, unresolved_warning (empty unless a quarter of the "
        "pairs or more are unresolved). Raises fvm.InputError for "
        "an incomplete grid or tiles of different sizes.\n\nExample:\n"
        "    >>> r = fvm.stitch([t00, t01, t10, t11], [(0, 0), (0, 1), (1, 0), (1, 1)], overlap=0.25)\n"
        "    >>> r['positions']");
}

}  // namespace fvm::python

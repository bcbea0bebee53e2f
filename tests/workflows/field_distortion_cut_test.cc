// Does `fvm stitch --distortion` generalise beyond the one real grid it was proven on? Real texture with a known
// field and known positions: the authors' distortion-corrected confocal tiles (../shared/realdata/tiles/
// confocal-3x4/corrected, Rouwane, Texier, Passieux 2024) fused at their translations (TileConfiguration_case1.txt)
// into one undistorted mosaic; grids cut from it at jittered whole-pixel positions, each tile taken through a known
// field (each pixel integrated over its area, as a camera records it) and, optionally, vignetting and camera noise.
// Judged: the positions after the common offset, the field over the tile against the truth, the standardised
// position errors, the overlap NCC after; and what the summaries say of the registration the positions rest on.
// Skipped where ../shared is absent. FVM_DISTORTION_SWEEP=1 runs the whole table (10-30 minutes on a loaded
// machine) instead of the fast cases; FVM_DISTORTION_SWEEP=authors (or any part of a row's description) its rows.

#include <fmt/core.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/QR>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <sstream>

#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"
#include "imaging/io/tile_image.h"
#include "imaging/tile_mosaic.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"

namespace fvm::workflows {
namespace {

const std::filesystem::path kConfocal = std::filesystem::path(FVM_REALDATA_DIR) / "tiles" / "confocal-3x4";

// The corrected tiles fused at the authors' translations, cropped to where every pixel is covered; empty when absent.
const imaging::TileImage& UndistortedConfocalMosaic() {
  static const imaging::TileImage mosaic = [] {
    imaging::TileImage out;
    std::ifstream in(kConfocal / "TileConfiguration_case1.txt");
    if (!in) return out;
    const std::regex line(R"((\S+);\s*;\s*\((-?[\d.]+),\s*(-?[\d.]+)\))");
    std::vector<imaging::TileImage> tiles;
    std::vector<Eigen::Vector2d> at;
    std::string text;
    std::smatch m;
    while (std::getline(in, text)) {
      if (!std::regex_search(text, m, line)) continue;
      tiles.push_back(imaging::ReadTileImage(kConfocal / "corrected" / std::string(m[1])));
      at.emplace_back(std::stod(m[2]), std::stod(m[3]));
    }
    const imaging::Mosaic fused = imaging::FuseTiles(tiles, at);
    const imaging::TileImage& f = fused.image;
    int top = 0, bottom = static_cast<int>(f.rows()), left = 0, right = static_cast<int>(f.cols());
    const auto row_full = [&](int y) { return f.row(y).segment(left, right - left).array().isFinite().all(); };
    const auto col_full = [&](int x) { return f.col(x).segment(top, bottom - top).array().isFinite().all(); };
    for (bool changed = true; changed;) {
      changed = false;
      if (top < bottom && !row_full(top)) ++top, changed = true;
      if (bottom > top && !row_full(bottom - 1)) --bottom, changed = true;
      if (left < right && !col_full(left)) ++left, changed = true;
      if (right > left && !col_full(right - 1)) --right, changed = true;
    }
    out = f.block(top, left, bottom - top, right - left);
    return out;
  }();
  return mosaic;
}

imaging::FieldDistortion MakeField(int size, const std::vector<std::pair<std::string, double>>& terms) {
  imaging::FieldDistortion f;
  f.width_px = f.height_px = size;
  f.order = 3;
  const std::vector<std::string>& names = imaging::FieldDistortionTermNames(3);
  f.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  for (const auto& [name, value] : terms) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw std::invalid_argument("no term " + name);
    f.coefficients(it - names.begin()) = value;
  }
  return f;
}

// The fields of the table, `edge_px` their size at the tile edge. "authors": the shape of the field the authors
// identified on the confocal grid (identif_case1.json, read as monomials [1, x, y, xy, x^2, y^2, x^2 y, x y^2] about
// the tile centre, x and y in [-1, 1]: 11.6 px of x y^2 in dx, -23.3 px of x^2 y in dy, tenths of a pixel of
// quadratic terms), scaled so that its largest coefficient is edge_px.
imaging::FieldDistortion NamedField(const std::string& kind, int size, double edge_px) {
  if (kind == "none") return {};
  if (kind == "authors") {
    // The monomials through the model's terms (radial and tangential first: FieldDistortionTermNames), by least
    // squares over the tile: exact, the terms span every monomial of degree 2 and 3.
    const double s = edge_px / 23.34;
    imaging::FieldDistortion f = MakeField(size, {});
    Eigen::MatrixXd a(2 * 289, f.coefficients.size());
    Eigen::VectorXd b(2 * 289);
    for (int k = 0; k < 289; ++k) {
      const Eigen::Vector2d u((k % 17) * (size - 1) / 16.0, (k / 17) * (size - 1) / 16.0);
      const double x = (u.x() - 0.5 * (size - 1)) / (0.5 * size), y = (u.y() - 0.5 * (size - 1)) / (0.5 * size);
      a.middleRows(2 * k, 2) = f.Basis(u);
      b(2 * k) = s * (0.406 * x * y - 0.151 * y * y - 0.197 * x * x * y + 11.63 * x * y * y);
      b(2 * k + 1) = s * (-0.371 * x * y + 0.050 * x * x - 23.34 * x * x * y - 0.171 * x * y * y);
    }
    f.coefficients = a.colPivHouseholderQr().solve(b);
    return f;
  }
  if (kind == "barrel") return MakeField(size, {{"k1", -edge_px}});
  if (kind == "pincushion") return MakeField(size, {{"k1", edge_px}});
  if (kind == "tangential") return MakeField(size, {{"p1", 0.6 * edge_px}, {"p2", -0.4 * edge_px}});
  throw std::invalid_argument("no field " + kind);
}

// A raw pixel as a camera records it: the mean over its area (k x k points) of the ideal image where the field sends
// each point, interpolated by Keys' cubic (a = -0.5). Not imaging::DistortTile, which takes one point a pixel through
// OpenCV's cubic (a = -0.75): that kernel shifts what a pixel shows by a few hundredths of a pixel depending on the
// fraction of u + d(u), which at whole pixels u is the fraction of d(u), the same in every tile (one field), so every
// overlap of one direction shares the error: a stretch of the mosaic in the truth. On the fast case below it was
// 0.03 px over two steps, the standardised position errors' rms 1.73 (0.92 integrated; one point a pixel through
// Keys' a = -0.5: 0.55; FVM_CUT_POINT_SAMPLED=1 cuts as before).
imaging::TileImage IntegrateThroughField(const imaging::TileImage& ideal_with_margin, int margin_px,
                                         const imaging::FieldDistortion& field, int k = 3) {
  const int w = static_cast<int>(ideal_with_margin.cols()) - 2 * margin_px;
  const int h = static_cast<int>(ideal_with_margin.rows()) - 2 * margin_px;
  const auto weights = [](double f) {
    const auto keys = [](double t) {
      t = std::abs(t);
      return t <= 1.0 ? (1.5 * t - 2.5) * t * t + 1.0 : ((-0.5 * t + 2.5) * t - 4.0) * t + 2.0;
    };
    return Eigen::Vector4d(keys(1.0 + f), keys(f), keys(1.0 - f), keys(2.0 - f));
  };
  imaging::TileImage out(h, w);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double sum = 0.0;
      for (int j = 0; j < k; ++j) {
        for (int i = 0; i < k; ++i) {
          const Eigen::Vector2d point(x + (i + 0.5) / k - 0.5, y + (j + 0.5) / k - 0.5);
          const Eigen::Vector2d at = point + field.Displacement(point) + Eigen::Vector2d::Constant(margin_px);
          const int ix = static_cast<int>(std::floor(at.x())), iy = static_cast<int>(std::floor(at.y()));
          const Eigen::Matrix4d window = ideal_with_margin.block<4, 4>(iy - 1, ix - 1).cast<double>();
          sum += weights(at.y() - iy).dot(window * weights(at.x() - ix));
        }
      }
      out(y, x) = static_cast<float>(sum / (k * k));
    }
  }
  return out;
}

struct CutCase {
  std::string field = "authors";
  double edge_px = 10.0;
  int rows = 3, cols = 3, size = 512;
  double overlap = 0.15;
  double vignetting = 0.0;  // fall-off of the gain at the corners
  double jitter_px = 8.0;   // each tile off its nominal place by up to this, per axis (uniform)
  uint32_t seed = 1;
  // The stage's skew as the held-out confocal grids show it: each row starts skew_px further along x than the one
  // above, and y drifts by drift_px from column to column; the layout in serpentine order (row 0 left to right, row 1
  // back); the tiles at `missing` (row, col) left out of it (the holes a layout read from Fiji's TileConfiguration
  // by a pattern without signs leaves where a position is negative).
  double skew_px = 0.0, drift_px = 0.0;
  bool serpentine = false;
  std::vector<std::pair<int, int>> missing;
};

struct CutGrid {
  imaging::TileLayout layout;
  std::vector<imaging::TileImage> images;
  std::vector<Eigen::Vector2d> truth_px;  // relative to the first tile
  imaging::FieldDistortion field;
};

CutGrid CutDistortedGrid(const imaging::TileImage& source, const CutCase& c) {
  CutGrid g;
  g.field = NamedField(c.field, c.size, c.edge_px);
  std::mt19937 rng(c.seed);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0); };
  const int margin = static_cast<int>(std::ceil(g.field.Identity() ? 0.0 : g.field.LargestDisplacementPx())) + 4;
  const double step = c.size * (1.0 - c.overlap);
  const double skew_x = (c.rows - 1) * std::abs(c.skew_px), skew_y = (c.cols - 1) * std::abs(c.drift_px);
  const int span_x = static_cast<int>(std::ceil((c.cols - 1) * step + 2 * c.jitter_px + skew_x)) + c.size + 2 * margin;
  const int span_y = static_cast<int>(std::ceil((c.rows - 1) * step + 2 * c.jitter_px + skew_y)) + c.size + 2 * margin;
  if (span_x > source.cols() || span_y > source.rows()) throw std::invalid_argument("the grid does not fit");
  const int x0 = static_cast<int>(uniform(0, static_cast<double>(source.cols() - span_x))) + margin +
                 static_cast<int>(c.jitter_px + (c.skew_px < 0 ? skew_x : 0.0));
  const int y0 = static_cast<int>(uniform(0, static_cast<double>(source.rows() - span_y))) + margin +
                 static_cast<int>(c.jitter_px + (c.drift_px < 0 ? skew_y : 0.0));
  std::normal_distribution<double> noise(0.0, 1.0);
  double lo = source.minCoeff(), hi = source.maxCoeff();
  Eigen::Vector2i first(0, 0);
  for (int r = 0; r < c.rows; ++r) {
    for (int k = 0; k < c.cols; ++k) {
      const int col = c.serpentine && r % 2 == 1 ? c.cols - 1 - k : k;
      const Eigen::Vector2i p(
          x0 + static_cast<int>(std::lround(col * step + r * c.skew_px + uniform(-c.jitter_px, c.jitter_px))),
          y0 + static_cast<int>(std::lround(r * step + col * c.drift_px + uniform(-c.jitter_px, c.jitter_px))));
      if (std::find(c.missing.begin(), c.missing.end(), std::pair{r, col}) != c.missing.end()) continue;
      if (g.images.empty()) first = p;
      const imaging::TileImage ideal =
          source.block(p.y() - margin, p.x() - margin, c.size + 2 * margin, c.size + 2 * margin);
      imaging::TileImage tile = g.field.Identity()           ? imaging::TileImage(ideal.block(margin, margin, c.size, c.size))
                                : std::getenv("FVM_CUT_POINT_SAMPLED") ? imaging::DistortTile(ideal, margin, g.field)
                                                                       : IntegrateThroughField(ideal, margin, g.field);
      const double fall = c.vignetting * uniform(0.5, 1.0), half = 0.5 * (c.size - 1);
      for (int y = 0; y < c.size; ++y) {
        for (int x = 0; x < c.size; ++x) {
          const double shade = 1.0 - fall * ((x - half) * (x - half) + (y - half) * (y - half)) / (2 * half * half);
          tile(y, x) = static_cast<float>(shade * tile(y, x) + 0.01 * (hi - lo) * noise(rng));
        }
      }
      g.truth_px.push_back((p - first).cast<double>());
      g.layout.tiles.push_back({fmt::format("r{}c{}.tif", r, col), r, col, std::nullopt,
                                static_cast<int>(g.images.size() + 2), std::nullopt});
      g.images.push_back(std::move(tile));
    }
  }
  g.layout.rows = c.rows, g.layout.cols = c.cols;
  return g;
}

struct CutOutcome {
  bool refused = false;
  std::string why;
  double rigid_rms = NAN, rms = NAN, affine_rms = NAN, z_rms = NAN, field_rms = NAN, gauge_field_rms = NAN;
  double ncc_before = NAN, ncc_after = NAN, field_sigma = NAN;
  int accepted = 0, pairs = 0, again = 0;
};

// rms over the tile (17 x 17 points, per axis) of the difference of two fields; `gauge`: after the part that the
// overlaps cannot tell (the linear part, and the stretch terms stitching holds) is fitted out of the difference.
// rms over the tile (17 x 17 points, per axis) of the difference of two fields; `gauge`: after the part that the
// overlaps cannot tell is fitted out of the difference: the linear part, and the odd powers of one coordinate alone
// that stitching holds (x^3, y^3 in dx and in dy: imaging::kHeldStretchTerms).
double FieldGap(const imaging::FieldDistortion& found, const imaging::FieldDistortion& truth, int size, bool gauge) {
  const int k = 17 * 17;
  Eigen::MatrixXd basis = Eigen::MatrixXd::Zero(2 * k, 10);
  Eigen::VectorXd v(2 * k);
  for (int p = 0; p < k; ++p) {
    const Eigen::Vector2d u((p % 17) * (size - 1) / 16.0, (p / 17) * (size - 1) / 16.0);
    v.segment<2>(2 * p) = (found.Identity() ? Eigen::Vector2d::Zero() : found.Displacement(u)) -
                          (truth.Identity() ? Eigen::Vector2d::Zero() : truth.Displacement(u));
    const double x = (u.x() - 0.5 * (size - 1)) / (0.5 * size), y = (u.y() - 0.5 * (size - 1)) / (0.5 * size);
    basis.block(2 * p, 0, 1, 5) << 1.0, x, y, x * x * x, y * y * y;
    basis.block(2 * p + 1, 5, 1, 5) << 1.0, x, y, x * x * x, y * y * y;
  }
  if (gauge) v -= basis * basis.colPivHouseholderQr().solve(v);
  return std::sqrt(v.squaredNorm() / (2.0 * k));
}

CutOutcome StitchCutGrid(const CutGrid& g, const CutCase& c) {
  CutOutcome out;
  StitchOptions options;
  options.overlap = c.overlap;
  options.threads = 2;
  const StitchResult rigid = StitchTiles(g.layout, g.images, options);
  out.accepted = rigid.accepted, out.pairs = static_cast<int>(rigid.registration.pairs.size());
  const size_t n = g.images.size();
  const auto offset_rms = [&](const std::vector<Eigen::Vector2d>& mine, const std::vector<Eigen::Vector2d>* sigma,
                              double* z_rms) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < n; ++i) mean += mine[i] - g.truth_px[i];
    mean /= static_cast<double>(n);
    double sum = 0.0, z = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d e = mine[i] - g.truth_px[i] - mean;
      sum += e.squaredNorm();
      // The standardised errors against the first tile, as the u are (the errors about the mean offset, which
      // share the first tile's error less, read 1.35 times smaller on the fast case).
      if (sigma && i > 0) z += (mine[i] - mine[0] - g.truth_px[i]).cwiseQuotient((*sigma)[i]).squaredNorm();
    }
    if (z_rms) *z_rms = std::sqrt(z / (2.0 * static_cast<double>(n - 1)));
    return std::sqrt(sum / static_cast<double>(n));
  };
  out.rigid_rms = offset_rms(rigid.registration.positions.positions_px, nullptr, nullptr);
  out.ncc_before = rigid.mean_overlap_ncc;
  if (std::getenv("FVM_DISTORTION_PAIRS")) {
    for (const imaging::PairRegistration& p : rigid.registration.pairs) {
      fmt::print("  pair {}-{}: q {:.3f} {} {}\n", p.a, p.b, p.quality, p.accepted ? "ok" : "REJECTED", p.rejection);
    }
    for (const std::string& o : rigid.overruled) fmt::print("  overruled {}\n", o);
  }
  StitchDistortionResult r;
  try {
    StitchDistortionOptions distortion;
    // FVM_DISTORTION_FREE=1: the stretch terms identified too (imaging::kHeldStretchTerms), to see what the
    // overlaps tell of them.
    distortion.hold_stretch_terms = !std::getenv("FVM_DISTORTION_FREE");
    r = StitchWithoutDistortion(rigid, g.images, distortion);
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    out.refused = true, out.why = e.what();
    return out;
  }
  out.rms = offset_rms(r.fit.positions_px, &r.sigma_px, &out.z_rms);
  if (std::getenv("FVM_DISTORTION_TILES")) {
    for (size_t i = 0; i < n; ++i) {
      fmt::print("  tile {} r{}c{}: error {:+.3f} {:+.3f} u {:.3f} {:.3f}; rigid error {:+.3f} {:+.3f} u {:.3f} {:.3f}\n", i,
                 g.layout.tiles[i].row, g.layout.tiles[i].col, (r.fit.positions_px[i] - r.fit.positions_px[0] - g.truth_px[i]).x(),
                 (r.fit.positions_px[i] - r.fit.positions_px[0] - g.truth_px[i]).y(), r.sigma_px[i].x(), r.sigma_px[i].y(),
                 (rigid.registration.positions.positions_px[i] - rigid.registration.positions.positions_px[0] - g.truth_px[i]).x(),
                 (rigid.registration.positions.positions_px[i] - rigid.registration.positions.positions_px[0] - g.truth_px[i]).y(),
                 rigid.registration.positions.sigma_px[i].x(), rigid.registration.positions.sigma_px[i].y());
    }
    const imaging::StageAxesPrior& p = rigid.registration.stage_axes;
    fmt::print("  prior own {:.3f} {:.3f} column step {:.3f} {:.3f} row step {:.3f} {:.3f}; stage sigma {:.3f}\n", p.own_px.x(),
               p.own_px.y(), p.column_step_px.x(), p.column_step_px.y(), p.row_step_px.x(), p.row_step_px.y(),
               rigid.registration.stage_sigma_px);
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(n), 3), b(static_cast<Eigen::Index>(n), 2);
  for (size_t i = 0; i < n; ++i) {
    a.row(static_cast<Eigen::Index>(i)) << r.fit.positions_px[i].x(), r.fit.positions_px[i].y(), 1.0;
    b.row(static_cast<Eigen::Index>(i)) = g.truth_px[i].transpose();
  }
  out.affine_rms = std::sqrt((b - a * a.colPivHouseholderQr().solve(b)).squaredNorm() / static_cast<double>(n));
  out.field_rms = FieldGap(r.fit.field, g.field, c.size, false);
  out.gauge_field_rms = FieldGap(r.fit.field, g.field, c.size, true);
  out.field_sigma = r.fit.field.DisplacementSigmaPx();
  out.ncc_after = r.mean_overlap_ncc_after;
  out.again = r.pairs_registered_undistorted;
  return out;
}

std::string Describe(const CutCase& c) {
  std::string shape;
  if (c.skew_px != 0.0 || c.drift_px != 0.0) shape += fmt::format(" skew {}/{}", c.skew_px, c.drift_px);
  if (c.serpentine) shape += " serp";
  for (const auto& [r, col] : c.missing) shape += fmt::format(" -{}{}", r, col);
  return fmt::format("{:>2.0f} % {}x{} {:>4} px {:>10} {:>4.1f} px{} s{}{}", 100 * c.overlap, c.rows, c.cols, c.size,
                     c.field, c.field == "none" ? 0.0 : c.edge_px, c.vignetting > 0 ? " vign" : "     ", c.seed, shape);
}

void PrintOutcome(const CutCase& c, const CutOutcome& o) {
  if (o.refused) {
    fmt::print("{} | refused: {}\n", Describe(c), o.why);
    return;
  }
  fmt::print("{} | pairs {:>2}+{}/{:<2} | pos {:6.3f} (rigid {:6.2f}, affine {:6.3f}) | field {:6.3f} gauge {:6.3f} "
             "(u {:5.3f}) | z {:5.2f} | ncc {:.3f} -> {:.3f}\n",
             Describe(c), o.accepted, o.again, o.pairs, o.rms, o.rigid_rms, o.affine_rms, o.field_rms, o.gauge_field_rms,
             o.field_sigma, o.z_rms, o.ncc_before, o.ncc_after);
}

// The fast case: a 3 x 3 grid of 320 px tiles cut from one corrected confocal tile, 10 % overlap, through the
// authors' field at 8 px. Its x^2 y in dy shears the vertical overlaps by up to 2 x 0.9 x 8 px along the band, so
// some of them do not register on the raw tiles (quality below 0.5): those tiles stayed at their stage positions,
// pixels off, until the grid was registered again on the tiles resampled without the first field found.
TEST(CutConfocalGrid, PairsTheFieldShearsRegisterOnceUndistorted) {
  const std::filesystem::path file = kConfocal / "corrected" / "x100_epr-jerem_10pct_001_A006_I.tif";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "../shared/realdata absent";
  const imaging::TileImage source = imaging::ReadTileImage(file);
  CutCase c;
  c.field = "authors", c.edge_px = 8.0, c.rows = 3, c.cols = 3, c.size = 320, c.overlap = 0.10, c.seed = 1;
  const CutGrid g = CutDistortedGrid(source, c);
  const CutOutcome o = StitchCutGrid(g, c);
  PrintOutcome(c, o);
  ASSERT_FALSE(o.refused) << o.why;
  EXPECT_LT(o.accepted, o.pairs);  // the gap: the raw tiles leave pairs unregistered ...
  EXPECT_GT(o.again, 0);           // ... that register once undistorted
  EXPECT_GT(o.rigid_rms, 1.0);
  // Goals of issue 43: positions within 0.5 px (0.0x measured), the field within 0.1 px rms over the tile.
  EXPECT_LT(o.rms, 0.1);
  EXPECT_LT(o.field_rms, 0.1);
  EXPECT_GT(o.ncc_after, o.ncc_before + 0.2);
  // The positions' u honest: standardised errors' rms 1.25 (16 values sharing the first tile's error, about 8
  // independent: such an rms falls within 0.5-1.5 when the u are right; 2.53 when the truth was cut point-sampled,
  // IntegrateThroughField).
  EXPECT_GT(o.z_rms, 0.6);
  EXPECT_LT(o.z_rms, 1.5);
}

// What the summaries say once the grid registered again on the undistorted tiles: the tiles that registration places
// are registered (the positions CSV, --json's stage_fallback, the text, the report, Python's fvm.stitch), not
// what the first pass on the raw tiles left at their stage positions.
TEST(CutConfocalGrid, SummariesDescribeTheRegistrationOnTheUndistortedTiles) {
  const std::filesystem::path file = kConfocal / "corrected" / "x100_epr-jerem_10pct_001_A006_I.tif";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "../shared/realdata absent";
  CutCase c;
  c.field = "authors", c.edge_px = 8.0, c.rows = 3, c.cols = 3, c.size = 320, c.overlap = 0.10, c.seed = 1;
  const CutGrid g = CutDistortedGrid(imaging::ReadTileImage(file), c);
  StitchLayoutOptions options;
  options.stitch.overlap = c.overlap;
  options.stitch.threads = 2;
  options.distortion = StitchDistortionOptions{};
  const StitchedLayout s = StitchLayout(g.layout, g.images, options);
  ASSERT_TRUE(s.field);
  // The first pass on the raw tiles: three pairs the field shears did not register, and the tiles below the first
  // row hang on pairs that fix one direction (registered 0).
  const std::vector<std::string> lower = {"r1c0.tif", "r1c1.tif", "r1c2.tif", "r2c0.tif", "r2c1.tif", "r2c2.tif"};
  EXPECT_EQ(s.rigid.accepted, 9);
  EXPECT_EQ(s.rigid.stage_along_one_axis, lower);
  // Registered again on the undistorted tiles, every pair places them, on both axes.
  ASSERT_EQ(s.field->pairs_registered_undistorted, 3);
  ASSERT_TRUE(s.registered_undistorted);
  EXPECT_EQ(&s.Registered(), &*s.registered_undistorted);
  EXPECT_EQ(s.Registered().registration.pairs.size(), s.field->registration.pairs.size());
  EXPECT_EQ(s.Registered().accepted, 12);
  EXPECT_TRUE(s.Registered().at_stage_position.empty());
  EXPECT_TRUE(s.Registered().stage_along_one_axis.empty());

  std::string registered;  // the positions CSV's column, tile by tile
  std::istringstream csv(PositionsCsv(s));
  std::string line;
  std::getline(csv, line);
  ASSERT_EQ(line, "file,x,y,registered,u_x,u_y");
  while (std::getline(csv, line)) registered += line.substr(line.find(',', line.find(',', line.find(',') + 1) + 1) + 1, 1);
  EXPECT_EQ(registered, "111111111");

  const Summary summary = Summarize(s);
  EXPECT_EQ(summary.json["pairs_accepted"], 12);
  EXPECT_EQ(summary.json["stage_fallback"], nlohmann::ordered_json::array());
  EXPECT_EQ(summary.json["stage_along_one_axis"], nlohmann::ordered_json::array());
  EXPECT_EQ(summary.json["pairs_unresolved"], 0);
  for (const auto& pair : summary.json["pairs"]) EXPECT_TRUE(pair["accepted"].get<bool>()) << pair["a"] << " " << pair["b"];
  EXPECT_EQ(summary.json["distortion"]["pairs_registered_undistorted"], 3);
  EXPECT_NE(summary.text.find("12 pairs, 12 accepted (quality >= 0.5, on the tiles undistorted by the field)"),
            std::string::npos)
      << summary.text;
  EXPECT_EQ(summary.text.find("at their stage positions"), std::string::npos) << summary.text;
  EXPECT_EQ(summary.text.find("fix one direction"), std::string::npos) << summary.text;

  const report::StitchReportData page = StitchReport(s);
  const auto tiles = std::find_if(page.tables.begin(), page.tables.end(), [](const auto& t) { return t.heading == "Tile positions"; });
  ASSERT_NE(tiles, page.tables.end());
  for (const auto& row : tiles->rows) EXPECT_EQ(row.back(), "yes") << row.front();
  const auto pairs = std::find_if(page.summary.begin(), page.summary.end(), [](const auto& kv) { return kv.first == "pairs"; });
  ASSERT_NE(pairs, page.summary.end());
  EXPECT_EQ(pairs->second, "12 neighbour pairs: 12 accepted (0 overruled by the loops and replaced), 0 unresolved");
}

// Shaped like the held-out confocal grids (4 x 4 serpentine, 10 %, a skew of 6 px per row and 0.7 px per column),
// with holes at two corners, the first tile of the scan among them: cut from the authors' mosaic at 384 px through
// their field (8.7 px at the edge, 23.3 at 1024 px). The raw tiles leave pairs unregistered and the rigid positions
// pixels off; with the field every tile is placed (0.012 px rms measured at 640 px, goal 0.5) with honest u.
TEST(CutConfocalGrid, HeldOutShapeWithHolesAtCorners) {
  const imaging::TileImage& source = UndistortedConfocalMosaic();
  if (source.size() == 0) GTEST_SKIP() << "../shared/realdata absent";
  CutCase c;
  c.field = "authors", c.edge_px = 8.7, c.rows = 4, c.cols = 4, c.size = 384, c.overlap = 0.10, c.jitter_px = 1.5;
  c.skew_px = 6.0, c.drift_px = 0.7, c.serpentine = true, c.missing = {{0, 0}, {3, 0}}, c.seed = 12;
  const CutGrid g = CutDistortedGrid(source, c);
  ASSERT_EQ(g.images.size(), 14u);
  EXPECT_EQ(g.layout.tiles.front().col, 1);  // the scan's first tile is a hole: the layout starts at (0, 1)
  const CutOutcome o = StitchCutGrid(g, c);
  PrintOutcome(c, o);
  ASSERT_FALSE(o.refused) << o.why;
  EXPECT_EQ(o.pairs, 20);
  EXPECT_LT(o.rms, 0.1);
  EXPECT_LT(o.field_rms, 0.1);
  EXPECT_GT(o.z_rms, 0.5);
  EXPECT_LT(o.z_rms, 1.5);  // 13 tiles sharing the first one's error: the rms of a right u falls within 0.5-1.5
  EXPECT_GT(o.ncc_after, o.ncc_before + 0.2);
}

TEST(CutConfocalGrid, TheWholeTable) {
  if (!std::getenv("FVM_DISTORTION_SWEEP")) GTEST_SKIP() << "FVM_DISTORTION_SWEEP=1 runs the table";
  const imaging::TileImage& source = UndistortedConfocalMosaic();
  if (source.size() == 0) GTEST_SKIP() << "../shared/realdata absent";
  fmt::print("source mosaic {} x {} px\n", source.cols(), source.rows());
  std::vector<CutCase> cases;
  for (const std::string field : {"none", "authors", "barrel", "pincushion", "tangential"}) {
    for (const double overlap : {0.10, 0.15, 0.20, 0.30}) {
      CutCase c;
      c.field = field, c.overlap = overlap, c.size = 512, c.rows = 4, c.cols = 4;
      c.edge_px = field == "authors" ? 12.0 : 8.0;
      cases.push_back(c);
    }
  }
  // Larger tiles, other grids, vignetting, other seeds.
  const auto add = [&](const std::string& field, double edge, int rows, int cols, int size, double overlap,
                       double vignetting, uint32_t seed) {
    CutCase c;
    c.field = field, c.edge_px = edge, c.rows = rows, c.cols = cols, c.size = size, c.overlap = overlap;
    c.vignetting = vignetting, c.seed = seed;
    cases.push_back(c);
  };
  add("authors", 23.3, 3, 3, 1024, 0.15, 0.0, 2);
  add("authors", 23.3, 3, 3, 1024, 0.30, 0.3, 3);
  add("barrel", 15.0, 3, 3, 1024, 0.20, 0.3, 4);
  add("tangential", 5.0, 3, 3, 1024, 0.20, 0.0, 5);
  add("authors", 18.0, 4, 4, 768, 0.20, 0.3, 6);
  add("pincushion", 10.0, 3, 3, 768, 0.30, 0.3, 7);
  add("authors", 12.0, 5, 5, 512, 0.10, 0.3, 8);
  add("authors", 6.0, 5, 5, 512, 0.15, 0.0, 9);
  add("tangential", 5.0, 5, 5, 512, 0.20, 0.3, 10);
  add("barrel", 5.0, 5, 5, 512, 0.15, 0.0, 11);
  // Shaped like the held-out confocal grids: 4 x 4 serpentine, 10 %, a skew of 6 px per row and 0.7 px per column,
  // holes at corners and along an edge (640 px tiles: 4 x 4 of 1024 px do not fit in the source mosaic).
  for (const std::string field : {"none", "authors"}) {
    for (const std::vector<std::pair<int, int>>& missing : std::vector<std::vector<std::pair<int, int>>>{
             {}, {{0, 0}}, {{0, 0}, {3, 0}}, {{0, 3}, {3, 3}}, {{1, 0}, {2, 0}, {3, 0}}, {{0, 1}, {1, 0}}}) {
      CutCase c;
      c.field = field, c.edge_px = 14.6, c.rows = 4, c.cols = 4, c.size = 640, c.overlap = 0.10, c.jitter_px = 1.5;
      c.skew_px = 6.0, c.drift_px = 0.7, c.serpentine = true, c.missing = missing, c.seed = 12;
      cases.push_back(c);
    }
  }
  for (uint32_t seed = 13; seed <= 20; ++seed) {  // the first tile without neighbour: the stage's u, seed by seed
    CutCase c;
    c.field = "none", c.rows = 4, c.cols = 4, c.size = 640, c.overlap = 0.10, c.jitter_px = 1.5;
    c.skew_px = 6.0, c.drift_px = 0.7, c.serpentine = true, c.missing = {{0, 1}, {1, 0}}, c.seed = seed;
    cases.push_back(c);
  }
  const char* only = std::getenv("FVM_DISTORTION_SWEEP");
  for (const CutCase& c : cases) {
    if (std::string(only) != "1" && Describe(c).find(only) == std::string::npos) continue;
    PrintOutcome(c, StitchCutGrid(CutDistortedGrid(source, c), c));
  }
}

}  // namespace
}  // namespace fvm::workflows

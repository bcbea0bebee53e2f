// The real confocal grid of ../shared/realdata/tiles/confocal-3x4 (3 x 4 tiles of 1024 px, 10 % overlap, an
// objective and scanner that distort each tile by up to about 20 px towards its edges): fvm's positions of the
// undistorted tiles against the distortion-aware translations its authors identified (Rouwane, Texier, Passieux
// 2024: TileConfiguration_case1.txt), and the overlap correlation of the undistorted tiles. Skipped where ../shared
// is absent.

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <Eigen/QR>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include "imaging/io/tile_image.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"

namespace fvm::workflows {
namespace {

const std::filesystem::path kGrid = std::filesystem::path(FVM_REALDATA_DIR) / "tiles" / "confocal-3x4";

// A serpentine scan: A001-A004 the first row left to right, A005-A008 the second right to left, A009-A012 the third.
imaging::TileLayout ConfocalLayout() {
  imaging::TileLayout layout;
  for (int k = 0; k < 12; ++k) {
    const int row = k / 4, col = row == 1 ? 3 - k % 4 : k % 4;
    layout.tiles.push_back({fmt::format("x100_epr-jerem_10pct_001_A{:03d}_I.tif", k + 1), row, col, std::nullopt, k + 2,
                            std::nullopt});
  }
  layout.rows = 3, layout.cols = 4;
  return layout;
}

std::map<std::string, Eigen::Vector2d> FijiPositions(const std::filesystem::path& file) {
  std::map<std::string, Eigen::Vector2d> out;
  std::ifstream in(file);
  const std::regex line(R"((\S+);\s*;\s*\((-?[\d.]+),\s*(-?[\d.]+)\))");
  std::string text;
  std::smatch m;
  while (std::getline(in, text)) {
    if (std::regex_search(text, m, line)) out[m[1]] = Eigen::Vector2d(std::stod(m[2]), std::stod(m[3]));
  }
  return out;
}

TEST(ConfocalGrid, UndistortedPositionsMatchTheAuthorsTranslations) {
  if (!std::filesystem::exists(kGrid / "TileConfiguration_case1.txt")) GTEST_SKIP() << "../shared/realdata absent";
  const imaging::TileLayout layout = ConfocalLayout();
  std::vector<imaging::TileImage> images;
  for (const auto& t : layout.tiles) images.push_back(imaging::ReadTileImage(kGrid / t.file));
  StitchOptions options;
  options.overlap = 0.1;
  const StitchResult rigid = StitchTiles(layout, images, options);
  ASSERT_EQ(rigid.accepted, 17);
  const StitchDistortionResult r = StitchWithoutDistortion(rigid, images, {});
  const std::map<std::string, Eigen::Vector2d> theirs = FijiPositions(kGrid / "TileConfiguration_case1.txt");
  ASSERT_EQ(theirs.size(), 12u);
  // After the common offset: the mean difference over the tiles.
  const auto compare = [&](const std::vector<Eigen::Vector2d>& mine, const std::vector<Eigen::Vector2d>* sigma,
                           double* z_rms) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < 12; ++i) mean += mine[i] - theirs.at(layout.tiles[i].file);
    mean /= 12.0;
    double sum = 0.0, z = 0.0;
    for (size_t i = 0; i < 12; ++i) {
      const Eigen::Vector2d e = mine[i] - theirs.at(layout.tiles[i].file) - mean;
      sum += e.squaredNorm();
      // Standardised against the first tile, as the u are.
      const Eigen::Vector2d against_first = mine[i] - mine[0] - (theirs.at(layout.tiles[i].file) - theirs.at(layout.tiles[0].file));
      if (sigma && i > 0) z += against_first.cwiseQuotient((*sigma)[i]).squaredNorm();
    }
    if (z_rms) *z_rms = std::sqrt(z / 22.0);
    return std::sqrt(sum / 12.0);
  };
  double z_rms = 0.0;
  const double rigid_rms = compare(rigid.registration.positions.positions_px, nullptr, nullptr);
  const double rms = compare(r.fit.positions_px, &r.sigma_px, &z_rms);
  fmt::print("positions against the authors': rigid {:.3f} px rms, undistorted {:.3f} px rms (standardised {:.2f}); "
             "overlap NCC {:.3f} -> {:.3f}; field {:.2f} px largest, u {:.3f} px\n",
             rigid_rms, rms, z_rms, r.mean_overlap_ncc_before, r.mean_overlap_ncc_after,
             r.fit.field.LargestDisplacementPx(), r.fit.field.DisplacementSigmaPx());
  // The linear part of a field, and the terms that act on a grid's overlaps as a stretch or shear of the mosaic,
  // are what the overlaps do not tell (imaging/field_distortion.h); fvm holds them as the authors do (no x^3 in
  // dx, no y^3 in dy), so the positions agree after the common offset alone: 0.023 px rms measured (4.67 px when
  // the stretch terms were free, 0.4 % along x), and after a linear map to a hundredth of a pixel.
  const auto affine_rms = [&](const std::vector<Eigen::Vector2d>& mine) {
    Eigen::MatrixXd a(12, 3), b(12, 2);
    for (size_t i = 0; i < 12; ++i) {
      a.row(static_cast<Eigen::Index>(i)) << mine[i].x(), mine[i].y(), 1.0;
      b.row(static_cast<Eigen::Index>(i)) = theirs.at(layout.tiles[i].file).transpose();
    }
    const Eigen::MatrixXd e = b - a * a.colPivHouseholderQr().solve(b);
    return std::sqrt(e.squaredNorm() / 12.0);
  };
  const double rigid_affine = affine_rms(rigid.registration.positions.positions_px);
  const double affine = affine_rms(r.fit.positions_px);
  fmt::print("after a linear map: rigid {:.3f} px rms, undistorted {:.3f} px rms\n", rigid_affine, affine);
  EXPECT_LT(affine, 0.05);
  EXPECT_LT(affine, rigid_affine);
  EXPECT_LT(rms, 0.5);
  EXPECT_LT(rms, rigid_rms);
  // Honest: the errors against the authors' (their own error included) within the stated u.
  EXPECT_LE(z_rms, 1.25);
  // fvm's own overlap measure (bilinear); ../shared/bench/overlap_ncc.py reads 0.887 on the tiles fvm stitch
  // --undistorted writes, where the authors' corrected tiles reach 0.876.
  EXPECT_GT(r.mean_overlap_ncc_after, 0.876);
  EXPECT_GT(r.mean_overlap_ncc_after, r.mean_overlap_ncc_before + 0.1);
}

}  // namespace
}  // namespace fvm::workflows

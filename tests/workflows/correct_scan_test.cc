#include "workflows/correct_scan.h"

#include <gtest/gtest.h>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"
#include "workflows/calibrate.h"
#include "workflows/correct.h"

namespace fvm::workflows {
namespace {

stage::Calibration Calibrated() {
  artefacts::FvmBatchOptions sim;
  sim.seed = 8;
  return CalibrateBatch(artefacts::SimulateFvmBatch(sim).batch, {}).result.calibration;
}

// A scan's points are corrected exactly as centres at the same coordinates (the promise of docs/commands/correct.md: equal to 1 nm),
// uncertainties included; a NaN point is counted, not moved.
TEST(CorrectCloud, EveryPointAsACentreAtTheSameCoordinates) {
  const stage::Calibration cal = Calibrated();
  const std::vector<Eigen::Vector3d> points = {{-120, -80, -50.0}, {-60, -140, -49.9}, {-20, -30, -50.1}};
  std::vector<Eigen::Vector3d> with_nan = points;
  with_nan.push_back(Eigen::Vector3d::Constant(NAN));
  imaging::PointCloud cloud = imaging::MakeUnorganisedCloud(with_nan);
  const CorrectedCloud c = CorrectCloud(cloud, cal, {"cal.json", {}, false, 1}, "scan.ply", true);
  EXPECT_EQ(c.summary.corrected, 3u);
  EXPECT_EQ(c.summary.invalid, 1u);
  artefacts::CentreExport centres;
  for (size_t i = 0; i < points.size(); ++i) centres.centres.push_back({static_cast<int>(i + 1), points[i], {}, {}, {}, {}});
  const CentreCorrection expected = CorrectCentres(cal, centres, std::nullopt, "centres.csv");
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_LT((cloud.points[i] - expected.centres[i].position).norm(), 1e-6) << i;
    EXPECT_LT((c.u[i] - expected.centres[i].u).norm(), 1e-9) << i;
  }
}

TEST(CorrectCloud, PointsOutsideTheTravelAreRefusedByNameUnlessExtrapolated) {
  const stage::Calibration cal = Calibrated();
  imaging::PointCloud cloud = imaging::MakeUnorganisedCloud({{-120, -80, -50.0}, {900, -80, -50.0}});
  try {
    CorrectCloud(cloud, cal, {"cal.json", {}, false, 1}, "scan.ply", false);
    FAIL() << "a point 900 mm out was corrected";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scan.ply: 1 of its points lie outside the travel cal.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point 2 at stage (900.0000, -80.0000, -50.0000) mm"), std::string::npos) << e.what();
  }
  EXPECT_EQ(CorrectCloud(cloud, cal, {"cal.json", {}, true, 1}, "scan.ply", false).outside, (std::vector<std::size_t>{1}));
}

// Each tile moves by the model at its stage position (z: its median height), and says how far the per-point
// correction departs from that at its corners.
TEST(CorrectTiles, OneShiftPerTileAtItsStagePosition) {
  const stage::Calibration cal = Calibrated();
  const imaging::PointCloud a = imaging::MakeUnorganisedCloud({{-1, -1, -50.2}, {1, 1, -49.8}, {1, -1, -50.0}});
  const std::vector<TileInput> tiles = {{"a.x3p", "t/a.x3p", {-100, -80}, &a}, {"b.x3p", "t/b.x3p", {-40, -120}, &a}};
  const TileCorrection c = CorrectTiles(tiles, cal, {"cal.json", {}, false, 1}, "layout.csv");
  ASSERT_EQ(c.tiles.size(), 2u);
  for (const TileShift& t : c.tiles) {
    EXPECT_DOUBLE_EQ(t.centre.z(), -50.0);
    const stage::CorrectedPoint p = stage::Correct(cal, t.centre);
    EXPECT_LT((t.shift - (p.position - t.centre)).norm(), 1e-9);
    EXPECT_GT(t.per_point_mm, 0.0);
    EXPECT_LT(t.per_point_mm, 5e-3);  // the model's change over a 2.8 mm footprint: a few um
  }
  EXPECT_EQ(c.tiles[1].centre.x(), -40.0);
}

}  // namespace
}  // namespace fvm::workflows

// The test piece's geometry: the published piece as [Lorente 2021] counts it, and descriptions that cannot be made
// refused with the features named.

#include <gtest/gtest.h>

#include <map>

#include "artefacts/geometry/machined_piece.h"
#include "artefacts/simulation/machined_piece_simulation.h"
#include "core/input_error.h"

namespace fvm::artefacts {
namespace {

TEST(MachinedPiece, PublishedPieceHasThePublishedPointCountsAndSeries) {
  const MachinedPieceDescription piece = PublishedMachinedPiece();
  EXPECT_TRUE(piece.Problems().empty()) << piece.Problems().front();
  const std::vector<PiecePoint> points = NominalPoints(piece);
  EXPECT_EQ(points.size(), 480u);  // [Lorente 2021] 7.2.1
  std::map<std::string, int> series;
  int pyramid = 0;
  for (const PiecePoint& p : points) {
    ++series[p.series];
    pyramid += p.kind == FeatureKind::kPyramid ? 1 : 0;
  }
  EXPECT_EQ(pyramid, 167);  // [Lorente 2021] 7.2.2
  for (const char* s : {"X1", "X2", "X3", "Y1", "Y2", "Y3", "Z1", "Z2", "Z3"}) EXPECT_GE(series[s], 6) << s;
  // The description round-trips through its JSON.
  const MachinedPieceDescription again = ParseMachinedPiece(MachinedPieceJson(piece), "piece.json");
  ASSERT_EQ(NominalPoints(again).size(), points.size());
  EXPECT_EQ(NominalPoints(again)[100].machine, points[100].machine);
}

std::string Describe(const std::string& features) {
  return R"({"envelope_mm": [100, 100, 50], "features": [)" + features + "]}";
}

TEST(MachinedPiece, CollisionsAndEnvelopeErrorsNameTheFeatures) {
  const std::string slot = R"({"name": "S1", "kind": "slot", "min_mm": [10, 10, 40], "max_mm": [90, 30, 50]})";
  const std::string hole = R"({"name": "H7", "kind": "hole", "min_mm": [20, 20, 45], "max_mm": [25, 25, 50]})";
  const std::string wide = R"({"name": "P1", "kind": "pyramid", "min_mm": [40, 40, 30], "max_mm": [120, 80, 50]})";
  const std::string crossing = R"({"name": "S2", "kind": "slot", "min_mm": [10, 10, 40], "max_mm": [30, 90, 50]})";
  try {
    ParseMachinedPiece(Describe(slot + "," + hole), "p.json");
    FAIL() << "a hole inside a slot was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("slot S1 and hole H7 collide"), std::string::npos) << e.what();
  }
  try {
    ParseMachinedPiece(Describe(wide), "p.json");
    FAIL() << "a feature beyond the envelope was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pyramid P1 leaves the envelope: x from 40 to 120"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(ParseMachinedPiece(Describe(slot + "," + crossing), "p.json"));  // slots may cross
  try {
    ParseMachinedPiece(Describe(R"({"name": "Q", "kind": 3, "min_mm": [0, 0, 0], "max_mm": [1, 1, 1]})"), "p.json");
    FAIL() << "a kind that is no text was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p.json: feature Q"), std::string::npos) << e.what();
  }
}

TEST(MachinedPiece, PerfectMachineMeasuresTheNominalPointsAtTheDatum) {
  const MachinedPieceDescription piece = PublishedMachinedPiece();
  stage::AxisChain chain = stage::AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0, 0, 100);
  CmmSimulation cmm;
  cmm.datum.translation = Eigen::Vector3d(5, 6, 7);
  cmm.sigma_mm = 0.0;
  const MachineTruth perfect{PieceWorkspace(piece), {}};
  const std::vector<PiecePoint> points = NominalPoints(piece);
  const TrackerReadings r = SimulateMachinedPiece(chain, perfect, points, cmm);
  ASSERT_EQ(r.points.size(), points.size());
  EXPECT_TRUE(r.cmm);
  for (size_t i = 0; i < points.size(); i += 37) {
    EXPECT_LT((r.points[i].measured - (points[i].machine + chain.tool_offset - cmm.datum.translation)).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace fvm::artefacts

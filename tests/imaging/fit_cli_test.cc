// fvm fit as a user runs it: on an X3P export of a rendered 6 x 6 grid with a recorded truth, and on bad input.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/calotte_surface.h"
#include "artefacts/io/centre_export.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/x3p.h"
#include "tests/support/test_support.h"
#include "tests/support/run_fvm.h"

namespace fvm {
namespace {

using testing::FvmRun;
using testing::RunFvm;

TEST(FitCli, Grid6x6X3pToCentreExport) {
  testing::TempDir dir;
  artefacts::CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.02;  // 440 heights per calotte: a centre bound of 13 nm in z at 0.1 um noise
  o.margin_mm = 0.5;
  o.rotation_rad = -0.5 * M_PI / 180;
  o.offset_mm = Eigen::Vector2d(-20.0, 35.0);
  o.slope_y = 0.004;
  o.noise_sigma_mm = 1e-4;
  o.missing_fraction = 0.03;
  o.seed = 2;
  const artefacts::CalotteSurface surface = artefacts::RenderCalotteSurface(artefacts::CalotteGrid6x6(), o);
  const auto map_path = dir / "grid.x3p";
  imaging::WriteX3p(map_path, surface.map);
  const auto csv = dir / "grid.csv";

  const FvmRun run = RunFvm(dir, "fit " + map_path.string() + " --artefact grid6x6 -o " + csv.string() + " --json");
  ASSERT_EQ(run.status, 0) << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  ASSERT_EQ(doc["calottes"].size(), 36u);
  for (std::size_t i = 0; i < 36; ++i) {
    const auto& c = doc["calottes"][i];
    EXPECT_EQ(c["id"].get<int>(), static_cast<int>(i) + 1);
    const Eigen::Vector3d found(c["x"].get<double>(), c["y"].get<double>(), c["z"].get<double>());
    EXPECT_LT((found - surface.truth[i].centre).norm(), 1e-4) << "calotte " << i + 1;
    EXPECT_NEAR(c["radius"].get<double>(), 0.25, 2e-4);
    EXPECT_NEAR(c["form_rms_um"].get<double>(), 0.08, 0.03);  // 0.1 um height noise, cos-weighted
    EXPECT_GT(c["points"].get<int>(), 300);
    EXPECT_TRUE(c["converged"].get<bool>()) << c["fit_stop"];
    EXPECT_THAT(c["fit_stop"].get<std::string>(), ::testing::HasSubstr("at the minimum"));
  }
  EXPECT_NEAR(doc["layout"]["rotation_deg"].get<double>(), -0.5, 1e-3);

  const artefacts::CentreExport export_ = artefacts::ReadCentreExport(csv);
  ASSERT_EQ(export_.centres.size(), 36u);
  EXPECT_THAT(export_.comments.at(0), ::testing::HasSubstr("fvm fit"));
  for (const auto& c : export_.centres) {
    EXPECT_LT((c.position - surface.truth[static_cast<std::size_t>(c.id - 1)].centre).norm(), 1e-4 + 1e-6);
    ASSERT_TRUE(c.radius_mm && c.form_rms_mm);
  }
  // The fit status travels with the centres: a `converged` column, 1 for every calotte here.
  std::ifstream in(csv);
  std::string line;
  int rows = 0;
  bool header_seen = false;
  while (std::getline(in, line)) {
    if (line.starts_with("#")) continue;
    if (!header_seen) {
      EXPECT_EQ(line, "id,x,y,z,radius,form_rms,converged");
      header_seen = true;
      continue;
    }
    EXPECT_TRUE(line.ends_with(",1")) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 36);

  // The table names every calotte.
  const FvmRun table = RunFvm(dir, "fit " + map_path.string() + " --artefact grid6x6");
  ASSERT_EQ(table.status, 0) << table.err;
  EXPECT_THAT(table.out, ::testing::HasSubstr("grid6x6 layout: turned -0.500 deg"));
  EXPECT_THAT(table.out, ::testing::HasSubstr("\n  36  "));
}

// An unorganised cloud, as form-measurement software exports a calotte: found by grid projection, said so, and
// fitted to its own points.
TEST(FitCli, UnorganisedCloudOfOneCalotte) {
  testing::TempDir dir;
  artefacts::CalotteSurfaceOptions o;
  o.margin_mm = 0.4;
  o.offset_mm = Eigen::Vector2d(-100.0, -50.0);
  o.max_slope_deg = 70.0;
  o.noise_sigma_mm = 1e-4;
  o.seed = 5;
  const artefacts::CalotteCloud scene = artefacts::RenderCalotteCloud(artefacts::SingleCalotte(1.0), o, 40000);
  const auto ply = dir / "calotte.ply";
  imaging::WritePointCloud(ply, scene.cloud);
  const FvmRun run = RunFvm(dir, "fit " + ply.string() + " --json -o " + (dir / "c.csv").string());
  ASSERT_EQ(run.status, 0) << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  EXPECT_THAT(doc["method"].get<std::string>(), ::testing::HasSubstr("grid projection"));
  ASSERT_EQ(doc["calottes"].size(), 1u);
  const auto& c = doc["calottes"][0];
  const Eigen::Vector3d found(c["x"].get<double>(), c["y"].get<double>(), c["z"].get<double>());
  EXPECT_LT((found - scene.truth[0].centre).norm(), 2e-4);
  EXPECT_NEAR(c["radius"].get<double>(), 1.0, 2e-4);
  EXPECT_THAT(testing::ReadText(dir / "c.csv"), ::testing::HasSubstr("grid projection"));
}

TEST(FitCli, BadInputFailsWithoutOutput) {
  testing::TempDir dir;
  imaging::HeightMap empty;
  empty.size_x = 50;
  empty.size_y = 40;
  empty.dx_mm = empty.dy_mm = 0.01;
  empty.z_mm.assign(2000, NAN);
  const auto nan_map = dir / "nan.x3p";
  imaging::WriteX3p(nan_map, empty);
  const auto csv = dir / "out.csv";
  FvmRun run = RunFvm(dir, "fit " + nan_map.string() + " -o " + csv.string());
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr("no valid point"));
  EXPECT_FALSE(std::filesystem::exists(csv));

  imaging::HeightMap flat = empty;
  flat.z_mm.assign(2000, 0.0f);
  const auto flat_map = dir / "flat.x3p";
  imaging::WriteX3p(flat_map, flat);
  run = RunFvm(dir, "fit " + flat_map.string() + " -o " + csv.string());
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr("no calotte found"));
  EXPECT_FALSE(std::filesystem::exists(csv));

  run = RunFvm(dir, "fit " + flat_map.string() + " --artefact plate");
  EXPECT_NE(run.status, 0);
  EXPECT_THAT(run.err, ::testing::HasSubstr("grid6x6 or bar17"));
}

void WriteText(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

// fvm fit --shape: the JSON contract's keys in order, the numbers of the points it was given (a sphere of radius 2
// through 6 exact points in micrometres, a plane z = 1 of 4 points), and every bad input with exit 1 naming the file.
TEST(FitCli, ShapeJsonContract) {
  testing::TempDir dir;
  const auto sphere = dir / "ball.ds";  // NIST ATS layout: the count first; micrometres
  WriteText(sphere, "6\n2000 0 0\n-2000 0 0\n0 2000 0\n0 -2000 0\n0 0 2000\n0 0 -2000.5\n");
  FvmRun run = RunFvm(dir, "fit " + sphere.string() + " --shape sphere --unit um --json");
  ASSERT_EQ(run.status, 0) << run.err;
  nlohmann::json doc = nlohmann::json::parse(run.out);
  std::vector<std::string> keys;
  for (auto it = doc.begin(); it != doc.end(); ++it) keys.push_back(it.key());
  EXPECT_THAT(keys, ::testing::IsSupersetOf({"shape", "points", "centre_mm", "radius_mm", "u_centre_um",
                                             "u_radius_um", "rms_um", "outliers"}));
  EXPECT_EQ(doc["shape"], "sphere");
  EXPECT_EQ(doc["points"], 6);
  EXPECT_EQ(doc["outliers"], 0);
  EXPECT_NEAR(doc["radius_mm"].get<double>(), 2.0, 1e-3);
  EXPECT_NEAR(doc["centre_mm"][2].get<double>(), 0.0, 1e-3);
  EXPECT_GT(doc["u_radius_um"].get<double>(), 0.0);

  const auto plane = dir / "flat.xyz";
  WriteText(plane, "0 0 1\n1 0 1\n0 1 1\n1 1 1.001\n");
  run = RunFvm(dir, "fit " + plane.string() + " --shape plane --json");
  ASSERT_EQ(run.status, 0) << run.err;
  doc = nlohmann::json::parse(run.out);
  EXPECT_EQ(doc["shape"], "plane");
  EXPECT_NEAR(doc["point_mm"][2].get<double>(), 1.00025, 1e-12);  // the centroid
  EXPECT_NEAR(doc["normal"][2].get<double>(), 1.0, 1e-6);
  EXPECT_TRUE(doc.contains("u_normal_urad") && doc.contains("rms_um"));

  const auto few = dir / "few.xyz";
  WriteText(few, "0 0 0\n1 0 0\n0 1 0\n");
  run = RunFvm(dir, "fit " + few.string() + " --shape sphere");
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr(few.string() + ": 3 points cannot determine a sphere"));
  EXPECT_TRUE(run.out.empty());
  run = RunFvm(dir, "fit " + few.string() + " --shape sphere --unit m");
  EXPECT_EQ(run.status, 1);
  const auto line = dir / "line.xyz";
  WriteText(line, "0 0 0\n1 1 1\n2 2 2\n");
  run = RunFvm(dir, "fit " + line.string() + " --shape plane");
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr("lie on a line"));
  const auto nan = dir / "nan.xyz";
  WriteText(nan, "0 0 0\n1 0 0\n0 1 0\nnan 0 1\n0 0 1\n");
  run = RunFvm(dir, "fit " + nan.string() + " --shape sphere");
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr("point 4 of 5 has a NaN or infinite coordinate"));
  // A ball of 2 mm given in micrometres but read as metres: radius 2 km.
  run = RunFvm(dir, "fit " + sphere.string() + " --shape sphere --unit m");
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, ::testing::HasSubstr("is above 10 m"));
}

}  // namespace
}  // namespace fvm

// fvm correct on scans as a user runs it (issue 17): every point of a cloud or height map equals the centre-CSV
// correction of its coordinates to 1 nm, in every format; the sample's validation placements corrected into their
// first tiles' frames land on their stitched exports by the validation error fvm calibrate reports; heights keep
// the file's precision; bad input fails clearly and writes nothing.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fmt/core.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "artefacts/io/centre_export.h"
#include "core/number_text.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/x3p.h"
#include "stage/calibration.h"
#include "stage/io/calibration_file.h"
#include "tests/support/test_support.h"
#include "tests/support/run_fvm.h"

namespace fvm {
namespace {

using ::testing::HasSubstr;
using testing::RunFvm;

const std::string kSamples = FVM_SAMPLES;

// One calibration of the sample for the whole suite: fvm calibrate takes a second.
class CorrectCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    calibration_ = (*dir_ / "cal.json").string();
    const testing::FvmRun run = RunFvm(*dir_, "calibrate " + kSamples + "/bar17 --model 27 -o " + calibration_ + " --json");
    ASSERT_EQ(run.status, 0) << run.err;
    report_ = nlohmann::json::parse(run.out);
  }
  static void TearDownTestSuite() { delete dir_; }
  static testing::TempDir* dir_;
  static std::string calibration_;
  static nlohmann::json report_;
};
testing::TempDir* CorrectCli::dir_ = nullptr;
std::string CorrectCli::calibration_;
nlohmann::json CorrectCli::report_;

// The corrected centres of a centre export, by id.
std::vector<artefacts::CentreRecord> Centres(const std::filesystem::path& csv) { return artefacts::ReadCentreExport(csv).centres; }

// Points spread over the sample's calibrated travel (x, y in -200..0 mm), seeded.
std::vector<Eigen::Vector3d> StagePoints(int n, unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> x(-190.0, -10.0), y(-190.0, -10.0), z(-0.4, 0.4);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(x(random), y(random), z(random));
  return points;
}

std::string CentreCsv(const std::vector<Eigen::Vector3d>& points) {
  std::string csv = "id,x,y,z\n";
  for (std::size_t i = 0; i < points.size(); ++i) {
    csv += std::to_string(i + 1) + "," + FormatShortest(points[i].x()) + "," + FormatShortest(points[i].y()) + "," +
           FormatShortest(points[i].z()) + "\n";
  }
  return csv;
}

std::string PlyAscii(const std::vector<Eigen::Vector3d>& points) {
  std::string ply = "ply\nformat ascii 1.0\ncomment as CloudCompare writes it\nelement vertex " +
                    std::to_string(points.size()) + "\nproperty double x\nproperty double y\nproperty double z\n"
                    "property uchar red\nend_header\n";
  for (const Eigen::Vector3d& p : points) {
    ply += FormatShortest(p.x()) + " " + FormatShortest(p.y()) + " " + FormatShortest(p.z()) + " 200\n";
  }
  return ply;
}

std::string PlyBinary(const std::vector<Eigen::Vector3d>& points) {
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(points.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  for (const Eigen::Vector3d& p : points) ply.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
  return ply;
}

std::string PcdAscii(const std::vector<Eigen::Vector3d>& points) {
  std::string pcd = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\n"
                    "COUNT 1 1 1\nWIDTH " + std::to_string(points.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                    std::to_string(points.size()) + "\nDATA ascii\n";
  for (const Eigen::Vector3d& p : points) {
    pcd += FormatShortest(p.x()) + " " + FormatShortest(p.y()) + " " + FormatShortest(p.z()) + "\n";
  }
  return pcd;
}

// x y z u_x u_y u_z rows of a corrected XYZ file.
std::vector<std::array<double, 6>> XyzRows(const std::filesystem::path& path) {
  std::vector<std::array<double, 6>> rows;
  std::istringstream in(testing::ReadText(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'x') continue;
    std::istringstream fields(line);
    std::array<double, 6> row{};
    std::string word;
    for (double& v : row) {
      fields >> word;
      v = ParseDouble(word).value_or(NAN);
    }
    rows.push_back(row);
  }
  return rows;
}

TEST_F(CorrectCli, EveryCloudFormatEqualsTheCentreCorrectionTo1nm) {
  const testing::TempDir dir;
  const std::vector<Eigen::Vector3d> points = StagePoints(300, 17);
  for (const std::string frame : {"stage", "first-tile"}) {
    SCOPED_TRACE(frame);
    const auto centres_in = dir.Write("points.csv", CentreCsv(points));
    const auto centres_out = dir / ("points." + frame + ".corrected.csv");
    testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " " + centres_in.string() + " -o " +
                                          centres_out.string() + " --frame " + frame);
    ASSERT_EQ(run.status, 0) << run.err;
    const std::vector<artefacts::CentreRecord> reference = Centres(centres_out);
    ASSERT_EQ(reference.size(), points.size());

    struct Case {
      std::string name, content, output;
    };
    const std::vector<Case> cases = {{"cloud.xyz", "", "out.xyz"},          {"cloud-ascii.ply", PlyAscii(points), "out.ply"},
                                     {"cloud-binary.ply", PlyBinary(points), "out.ply"}, {"cloud.pcd", PcdAscii(points), "out.pcd"},
                                     {"cloud-ascii.ply", PlyAscii(points), "out.xyz"}};
    for (const Case& c : cases) {
      SCOPED_TRACE(c.name + " -> " + c.output);
      std::string content = c.content;
      if (content.empty()) {
        content = "# x y z in mm\n";
        for (const Eigen::Vector3d& p : points) {
          content += FormatShortest(p.x()) + " " + FormatShortest(p.y()) + " " + FormatShortest(p.z()) + "\n";
        }
      }
      const auto in = dir.Write(c.name, content);
      const auto out = dir / c.output;
      std::filesystem::remove(out);
      run = RunFvm(dir, "correct --calibration " + calibration_ + " " + in.string() + " -o " + out.string() +
                            " --frame " + frame + " --json");
      ASSERT_EQ(run.status, 0) << run.err;
      const nlohmann::json doc = nlohmann::json::parse(run.out);
      EXPECT_EQ(doc["frame"], frame);
      EXPECT_EQ(doc["corrected"], points.size());
      const imaging::PointCloud corrected = imaging::ReadPointCloud(out);
      ASSERT_EQ(corrected.points.size(), points.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        // The centre export holds 6 decimals (0.5 nm); the cloud the exact double.
        ASSERT_LT((corrected.points[i] - reference[i].position).cwiseAbs().maxCoeff(), 1e-6) << "point " << i + 1;
      }
      if (c.output == "out.xyz") {  // the uncertainties travel in the same file, equal to the centre export's
        const std::vector<std::array<double, 6>> rows = XyzRows(out);
        ASSERT_EQ(rows.size(), points.size());
        const std::vector<artefacts::CentreRecord> with_u = Centres(centres_out);
        const std::string text = testing::ReadText(centres_out);
        EXPECT_THAT(text, HasSubstr("# frame: " + frame));
        for (std::size_t i = 0; i < points.size(); ++i) EXPECT_GT(rows[i][3], 0.0);
        EXPECT_THAT(testing::ReadText(out), HasSubstr("frame: " + frame));
      }
    }
  }
}

// A height map: as an X3P with float64 heights in an inline DataList with empty <Datum/> elements (the OpenGPS
// samples' form), and as int16 counts with a Z increment and offset and a valid.bin mask. Each valid grid point
// corrects to the centre correction of its grid coordinates; the map becomes an organised cloud.
TEST_F(CorrectCli, HeightMapPointsEqualTheCentreCorrectionTo1nm) {
  const testing::TempDir dir;
  imaging::HeightMap map;
  map.size_x = 23;
  map.size_y = 17;
  map.dx_mm = 0.0125;
  map.dy_mm = 0.0125;
  map.x0_mm = -131.25;
  map.y0_mm = -87.5;
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix) {
      map.z_mm.push_back(0.0123 * std::sin(0.7 * ix + 1.3 * iy) - 0.004 + 1e-9 * ix * iy);
    }
  }
  map.z_mm[5] = NAN;
  map.z_mm[100] = NAN;
  imaging::X3pWriteOptions inline_d;
  inline_d.binary = false;
  imaging::X3pWriteOptions int16;
  int16.z_type = imaging::X3pDataType::kInt16;
  int16.z_increment_mm = 1e-6;
  const auto inline_path = dir / "inline-d.x3p";
  const auto int16_path = dir / "int16.x3p";
  imaging::WriteX3p(inline_path, map, inline_d);
  imaging::WriteX3p(int16_path, map, int16);

  for (const auto& path : {inline_path, int16_path}) {
    SCOPED_TRACE(path.filename().string());
    const imaging::HeightMap read = imaging::ReadX3p(path);
    std::vector<Eigen::Vector3d> grid;
    for (int iy = 0; iy < read.size_y; ++iy) {
      for (int ix = 0; ix < read.size_x; ++ix) {
        if (std::isfinite(read.at(ix, iy))) {
          grid.emplace_back(read.x0_mm + ix * read.dx_mm, read.y0_mm + iy * read.dy_mm, read.at(ix, iy));
        }
      }
    }
    const auto centres_in = dir.Write("grid.csv", CentreCsv(grid));
    const auto centres_out = dir / "grid.corrected.csv";
    testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " " + centres_in.string() + " -o " +
                                          centres_out.string());
    ASSERT_EQ(run.status, 0) << run.err;
    const std::vector<artefacts::CentreRecord> reference = Centres(centres_out);
    const auto out = dir / "map.ply";
    run = RunFvm(dir, "correct --calibration " + calibration_ + " " + path.string() + " -o " + out.string() + " --json");
    ASSERT_EQ(run.status, 0) << run.err;
    const nlohmann::json doc = nlohmann::json::parse(run.out);
    EXPECT_EQ(doc["invalid"], 2);
    EXPECT_EQ(doc["frame"], "stage");
    const imaging::PointCloud corrected = imaging::ReadPointCloud(out);
    ASSERT_EQ(corrected.width, map.size_x);  // still organised: the grid's neighbours stay neighbours
    ASSERT_EQ(corrected.height, map.size_y);
    std::size_t k = 0;
    for (const Eigen::Vector3d& p : corrected.points) {
      if (!p.allFinite()) continue;
      ASSERT_LT((p - reference.at(k).position).cwiseAbs().maxCoeff(), 1e-6) << "point " << k;
      ++k;
    }
    EXPECT_EQ(k, grid.size());
  }
}

// The frame story on the sample: its validation placements corrected with --frame first-tile land on their
// stitched exports by exactly the first-tile validation error fvm calibrate reports (the same centres, the same
// frame); in the default stage frame they are tens of micrometres away (the stage's error at each first tile).
TEST_F(CorrectCli, ValidationPlacementsInTheFirstTileFrameMatchTheReportedValidationError) {
  const testing::TempDir dir;
  ASSERT_EQ(report_["validation"]["stitched_frame"], "rotated");
  const double reported_rms_um = report_["validation"]["rms_um"].get<double>();
  const double reported_max_um = report_["validation"]["max_um"].get<double>();
  double sum_first = 0.0, sum_stage = 0.0, max_first = 0.0;
  int n = 0;
  for (int placement = 1; placement <= 10; ++placement) {
    const std::string name = fmt::format("val-{:02d}", placement);
    const auto first_tile = dir / (name + ".first-tile.csv");
    const auto stage = dir / (name + ".stage.csv");
    const std::string free = kSamples + "/bar17/" + name + ".free.csv";
    ASSERT_EQ(RunFvm(dir, "correct --calibration " + calibration_ + " " + free + " -o " + first_tile.string() +
                              " --frame first-tile").status, 0);
    ASSERT_EQ(RunFvm(dir, "correct --calibration " + calibration_ + " " + free + " -o " + stage.string()).status, 0);
    const artefacts::CentreExport stitched = artefacts::ReadCentreExport(kSamples + "/bar17/" + name + ".stitched.csv");
    const std::vector<artefacts::CentreRecord> a = Centres(first_tile), b = Centres(stage);
    for (std::size_t i = 0; i < a.size(); ++i) {
      const artefacts::CentreRecord* s = stitched.Find(a[i].id);
      ASSERT_NE(s, nullptr);
      const double d_first = (a[i].position - s->position).norm(), d_stage = (b[i].position - s->position).norm();
      sum_first += d_first * d_first;
      sum_stage += d_stage * d_stage;
      max_first = std::max(max_first, d_first);
      ++n;
    }
  }
  ASSERT_EQ(n, 170);
  // The exports round to 0.5 nm per coordinate: the figures agree to a few nm.
  EXPECT_NEAR(std::sqrt(sum_first / n) * 1e3, reported_rms_um, 0.005);
  EXPECT_NEAR(max_first * 1e3, reported_max_um, 0.005);
  EXPECT_GT(std::sqrt(sum_stage / n) * 1e3, 20.0);
  const std::string header = testing::ReadText(dir / "val-01.first-tile.csv");
  EXPECT_THAT(header, HasSubstr("# frame: first-tile"));
  EXPECT_THAT(testing::ReadText(dir / "val-01.stage.csv"), HasSubstr("# frame: stage"));
}

// --resample: a height map again, on a regular grid, each node on the corrected surface to 0.1 nm; and the
// uncertainties go to a side CSV.
TEST_F(CorrectCli, ResampledHeightMapAndItsUncertainties) {
  const testing::TempDir dir;
  imaging::HeightMap map;
  map.size_x = map.size_y = 41;
  map.dx_mm = map.dy_mm = 0.01;
  map.x0_mm = -90.0;
  map.y0_mm = -120.0;
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix) map.z_mm.push_back(0.002 * ix * map.dx_mm - 0.001 * iy * map.dy_mm);
  }
  const auto in = dir / "plane.x3p";
  imaging::WriteX3p(in, map);
  const auto out = dir / "plane.corrected.x3p";
  const testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " " + in.string() + " -o " +
                                              out.string() + " --resample 0.01 --json");
  ASSERT_EQ(run.status, 0) << run.err;
  const imaging::HeightMap corrected = imaging::ReadX3p(out);
  EXPECT_DOUBLE_EQ(corrected.dx_mm, 0.01);
  // The truth at a node (X, Y): the corrected surface F(x, y, plane(x, y)) where its x, y reach (X, Y), found by
  // fixed-point iteration on the model itself (stage::Correct, the centre correction).
  const stage::Calibration cal = stage::ReadCalibration(calibration_);
  const auto plane = [](double x, double y) { return 0.002 * (x + 90.0) - 0.001 * (y + 120.0); };
  int checked = 0;
  double worst = 0.0;
  for (int iy = 0; iy < corrected.size_y; ++iy) {
    for (int ix = 0; ix < corrected.size_x; ++ix) {
      if (!std::isfinite(corrected.at(ix, iy))) continue;
      const Eigen::Vector2d node(corrected.x0_mm + ix * corrected.dx_mm, corrected.y0_mm + iy * corrected.dy_mm);
      Eigen::Vector2d q = node;
      Eigen::Vector3d moved;
      for (int k = 0; k < 6; ++k) {
        moved = stage::Correct(cal, Eigen::Vector3d(q.x(), q.y(), plane(q.x(), q.y()))).position;
        q += node - moved.head<2>();
      }
      worst = std::max(worst, std::abs(corrected.at(ix, iy) - moved.z()));
      ++checked;
    }
  }
  EXPECT_GT(checked, 1500);
  EXPECT_LT(worst, 1e-7);  // 0.1 nm: the bilinear interpolation of a surface that is a plane to 0.1 nm per cell
  const std::string side = testing::ReadText(dir / "plane.corrected.uncertainty.csv");
  EXPECT_THAT(side, HasSubstr("x,y,u_x,u_y,u_z"));
}

// Outside the calibrated travel: refused, naming the points, nothing written; --origin moves a corner-origin
// export onto the stage; --extrapolate corrects anyway.
TEST_F(CorrectCli, OutOfTravelPointsAreNamedUnlessExtrapolated) {
  const testing::TempDir dir;
  const auto in = dir.Write("far.xyz", "-100 -50 0\n250 -50 0\n-30 -400 0\n");
  const auto out = dir / "far.ply";
  testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " " + in.string() + " -o " + out.string());
  EXPECT_EQ(run.status, 1);
  EXPECT_THAT(run.err, HasSubstr("2 of its points lie outside the travel"));
  EXPECT_THAT(run.err, HasSubstr("point 2 at stage (250.0000, -50.0000, 0.0000) mm"));
  EXPECT_THAT(run.err, HasSubstr("point 3 at stage"));
  EXPECT_FALSE(std::filesystem::exists(out));
  run = RunFvm(dir, "correct --calibration " + calibration_ + " " + in.string() + " -o " + out.string() + " --extrapolate --json");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["outside_travel"], 2);

  // The same point given relative to an origin at (-150, -80, 0): equal to the point given in stage
  // coordinates, moved back by the origin.
  const auto corner = dir.Write("corner.xyz", "50 30 0.1\n");
  const auto stage = dir.Write("stage.xyz", "-100 -50 0.1\n");
  ASSERT_EQ(RunFvm(dir, "correct --calibration " + calibration_ + " " + corner.string() + " -o " + (dir / "c.xyz").string() +
                            " --origin=-150,-80,0").status, 0);
  ASSERT_EQ(RunFvm(dir, "correct --calibration " + calibration_ + " " + stage.string() + " -o " + (dir / "s.xyz").string()).status, 0);
  const Eigen::Vector3d c = imaging::ReadPointCloud(dir / "c.xyz").points.at(0);
  const Eigen::Vector3d s = imaging::ReadPointCloud(dir / "s.xyz").points.at(0);
  EXPECT_LT((c + Eigen::Vector3d(-150, -80, 0) - s).norm(), 1e-9);
}

// --layout: each tile moved by one shift, the centre correction of its stage position (x, y from the layout, the
// tile's median height); a height-map tile stays a height map.
TEST_F(CorrectCli, LayoutMovesEachTileByTheModelAtItsPosition) {
  const testing::TempDir dir;
  dir.Write("a.xyz", "0 0 0.01\n0.5 0 0.02\n0 0.5 0.03\n");
  imaging::HeightMap tile;
  tile.size_x = tile.size_y = 3;
  tile.dx_mm = tile.dy_mm = 0.25;
  tile.z_mm = {0.0, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.007, 0.008};
  imaging::WriteX3p(dir / "b.x3p", tile);
  const auto layout = dir.Write("layout.csv", "file,row,col,x,y\na.xyz,0,0,-120,-40\nb.x3p,0,1,-117.5,-40\n");
  const auto out = dir / "corrected";
  const testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " --layout " + layout.string() +
                                              " -o " + out.string() + " --json");
  ASSERT_EQ(run.status, 0) << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  ASSERT_EQ(doc["tiles"].size(), 2u);
  const stage::Calibration cal = stage::ReadCalibration(calibration_);
  const Eigen::Vector3d centre_a(-120, -40, 0.02), centre_b(-117.5, -40, 0.004);
  const Eigen::Vector3d shift_a = stage::Correct(cal, centre_a).position - centre_a;
  const Eigen::Vector3d shift_b = stage::Correct(cal, centre_b).position - centre_b;
  const imaging::PointCloud a = imaging::ReadPointCloud(out / "a.xyz");
  ASSERT_EQ(a.points.size(), 3u);
  EXPECT_LT((a.points[1] - Eigen::Vector3d(0.5, 0, 0.02) - shift_a).norm(), 1e-9);
  const imaging::HeightMap b = imaging::ReadX3p(out / "b.x3p");
  EXPECT_NEAR(b.x0_mm, shift_b.x(), 1e-9);
  EXPECT_NEAR(b.y0_mm, shift_b.y(), 1e-9);
  EXPECT_NEAR(b.at(2, 2), 0.008 + shift_b.z(), 1e-9);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(doc["tiles"][1]["shift_um"][k].get<double>(), shift_b[k] * 1e3, 1e-9);
  EXPECT_GT(doc["largest_per_point_um"].get<double>(), 0.0);  // a tile of 0.5 mm: the model changes across it
  EXPECT_THAT(testing::ReadText(out / "shifts.csv"), HasSubstr("file,x,y,z,dx_um"));
}

TEST_F(CorrectCli, BadInputFailsClearlyAndWritesNothing) {
  const testing::TempDir dir;
  const auto out = dir / "out.ply";
  const auto expect_fails = [&](const std::filesystem::path& in, const std::string& message, const std::string& extra = "") {
    SCOPED_TRACE(in.filename().string());
    const testing::FvmRun run =
        RunFvm(dir, "correct --calibration " + calibration_ + " " + in.string() + " -o " + out.string() + extra);
    EXPECT_EQ(run.status, 1);
    EXPECT_THAT(run.err, HasSubstr(message));
    EXPECT_FALSE(std::filesystem::exists(out));
  };
  expect_fails(dir.Write("faces.ply", "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
                                      "end_header\n3 0 1 2\n"),
               "faces.ply");
  expect_fails(dir.Write("no-xyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nproperty float b\n"
                                       "property float c\nend_header\n1 2 3\n"),
               "no-xyz.ply");
  expect_fails(dir.Write("no-z.xyz", "x y intensity\n-100 -50 3\n"), "no column 'z'");
  expect_fails(dir.Write("all-nan.xyz", "nan nan nan\ninf 1 2\n"), "no valid point");
  // NaN and infinite points are skipped and counted, as height maps' invalid points are.
  const auto some_nan = dir.Write("some-nan.xyz", "-100 -50 0\nnan nan nan\n-99 -48 inf\n-98 -46 0.1\n");
  const testing::FvmRun run = RunFvm(dir, "correct --calibration " + calibration_ + " " + some_nan.string() + " -o " +
                                              (dir / "some-nan.xyz.out.xyz").string() + " --json");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["invalid"], 2);
  EXPECT_EQ(nlohmann::json::parse(run.out)["corrected"], 2);

  // A calibration of another chain (a machine tool's) does not correct a microscope's scan.
  std::string other = testing::ReadText(calibration_);
  const std::size_t at = other.find("\"YXFZ\"");
  ASSERT_NE(at, std::string::npos);
  other.replace(at, 6, "\"XFYZ\"");
  const auto other_path = dir.Write("other-chain.json", other);
  const auto scan = dir.Write("scan.xyz", "-100 -50 0\n");
  const testing::FvmRun other_run =
      RunFvm(dir, "correct --calibration " + other_path.string() + " " + scan.string() + " -o " + out.string());
  EXPECT_EQ(other_run.status, 1);
  EXPECT_THAT(other_run.err, HasSubstr("XFYZ"));
  EXPECT_FALSE(std::filesystem::exists(out));

  // A height map cannot be written from a scan without a grid to resample it on.
  const testing::FvmRun no_grid = RunFvm(dir, "correct --calibration " + calibration_ + " " + scan.string() + " -o " +
                                                  (dir / "scan.x3p").string());
  EXPECT_EQ(no_grid.status, 1);
  EXPECT_THAT(no_grid.err, HasSubstr("--resample"));
}

}  // namespace
}  // namespace fvm

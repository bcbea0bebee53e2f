#include "artefacts/io/batch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/input_error.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;


Placement MakePlacement(const std::string& name, std::vector<int> ids, double offset, bool timed) {
  Placement p;
  p.name = name;
  p.ids = std::move(ids);
  for (size_t i = 0; i < p.ids.size(); ++i) {
    const double k = static_cast<double>(i);
    p.stitched.emplace_back(-154.5487 + 4.0 * k, -115.4767 - 0.123456 * k, -50.3624);
    p.free.emplace_back(-154.5487 + 4.0 * k + offset, -115.4767 - 0.123456 * k - offset, -50.3624 + 0.0001 * k);
    if (timed) p.t_s.push_back(10.0 * k + 0.25);
  }
  return p;
}

void ExpectSamePlacement(const Placement& a, const Placement& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.ids, b.ids);
  ASSERT_EQ(a.stitched.size(), b.stitched.size());
  ASSERT_EQ(a.free.size(), b.free.size());
  for (size_t i = 0; i < a.ids.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(a.stitched[i][axis], b.stitched[i][axis], 1e-6) << a.name << " calotte " << a.ids[i];
      EXPECT_NEAR(a.free[i][axis], b.free[i][axis], 1e-6) << a.name << " calotte " << a.ids[i];
    }
  }
  ASSERT_EQ(a.t_s.size(), b.t_s.size());
  for (size_t i = 0; i < a.t_s.size(); ++i) EXPECT_NEAR(a.t_s[i], b.t_s[i], 1e-6);
}

TEST(Batch, RoundTripWithRolesAndTimes) {
  testing::TempDir dir;
  Batch batch;
  batch.placements = {MakePlacement("oblique", {1, 8, 15, 22}, 0.0123457, true),
                      MakePlacement("x", {1, 2, 3, 4, 5, 6}, -0.002, false),
                      MakePlacement("y", {31, 25, 19, 13, 7, 1}, 0.0045, true)};
  batch.has_roles = true;
  batch.identify = {"x", "y"};
  batch.validate = {"oblique"};
  batch.lens = "5x";
  WriteBatch(dir.path(), batch);
  EXPECT_THAT(dir.Entries(), ElementsAre("batch.json", "oblique.free.csv", "oblique.stitched.csv", "x.free.csv",
                                         "x.stitched.csv", "y.free.csv", "y.stitched.csv"));

  const Batch back = ReadBatch(dir.path());
  EXPECT_EQ(back.dir, dir.path());
  ASSERT_EQ(back.placements.size(), 3u);
  for (size_t i = 0; i < 3; ++i) ExpectSamePlacement(back.placements[i], batch.placements[i]);
  EXPECT_TRUE(back.has_roles);
  EXPECT_THAT(back.identify, ElementsAre("x", "y"));
  EXPECT_THAT(back.validate, ElementsAre("oblique"));
  EXPECT_EQ(back.lens, "5x");
  EXPECT_EQ(back.Get("y").ids, (std::vector<int>{31, 25, 19, 13, 7, 1}));
  EXPECT_THAT(InputErrorOf([&] { back.Get("z"); }), HasSubstr("no placement 'z'; the placements are oblique, x, y"));
}

TEST(Batch, WithoutBatchJsonEveryPlacementIdentifiesInNameOrder) {
  testing::TempDir dir;
  Batch batch;
  batch.placements = {MakePlacement("b", {1, 2}, 0.001, false), MakePlacement("a", {3, 4}, 0.001, false)};
  WriteBatch(dir.path(), batch);
  EXPECT_THAT(dir.Entries(), ElementsAre("a.free.csv", "a.stitched.csv", "b.free.csv", "b.stitched.csv"));
  const Batch back = ReadBatch(dir.path());
  EXPECT_FALSE(back.has_roles);
  ASSERT_EQ(back.placements.size(), 2u);
  EXPECT_EQ(back.placements[0].name, "a");
  EXPECT_THAT(back.identify, ElementsAre("a", "b"));
  EXPECT_THAT(back.validate, IsEmpty());
  EXPECT_EQ(back.lens, "");
}

TEST(Batch, FreeCentresFollowTheStitchedOrderAndTimesNeedEveryRow) {
  testing::TempDir dir;
  dir.Write("p.stitched.csv", "id,x,y,z\n6,20,0,0\n1,0,0,0\n");
  dir.Write("p.free.csv", "# t missing for calotte 6\nid,x,y,z,t\n1,0.001,0,0,5\n6,20.002,0,0,\n");
  dir.Write("q.stitched.csv", "id,x,y,z\n1,0,0,0\n2,4,0,0\n");
  dir.Write("q.free.csv", "id,x,y,z,t\n2,4.5,0,0,7.25\n1,0.5,0,0,1.5\n");
  const Batch batch = ReadBatch(dir.path());
  const Placement& p = batch.Get("p");
  EXPECT_EQ(p.ids, (std::vector<int>{6, 1}));
  EXPECT_EQ(p.free[0], Eigen::Vector3d(20.002, 0, 0));
  EXPECT_EQ(p.free[1], Eigen::Vector3d(0.001, 0, 0));
  EXPECT_THAT(p.t_s, IsEmpty());
  const Placement& q = batch.Get("q");
  EXPECT_EQ(q.ids, (std::vector<int>{1, 2}));
  EXPECT_THAT(q.t_s, ElementsAre(1.5, 7.25));
}

TEST(Batch, IdInOnlyOneFileNamesBothFilesAndTheCalotte) {
  testing::TempDir dir;
  dir.Write("x.stitched.csv", "id,x,y,z\n1,0,0,0\n6,20,0,0\n");
  dir.Write("x.free.csv", "id,x,y,z\n1,0,0,0\n6,20,0,0\n7,24,0,0\n");
  const std::string message = InputErrorOf([&] { ReadBatch(dir.path()); });
  EXPECT_THAT(message, HasSubstr((dir / "x.free.csv").string() + ":4: calotte 7 is not in"));
  EXPECT_THAT(message, HasSubstr((dir / "x.stitched.csv").string()));

  dir.Write("x.stitched.csv", "id,x,y,z\n1,0,0,0\n5,16,0,0\n6,20,0,0\n");
  const std::string other = InputErrorOf([&] { ReadBatch(dir.path()); });
  EXPECT_THAT(other, HasSubstr((dir / "x.stitched.csv").string() + ":3: calotte 5 is not in"));
  EXPECT_THAT(other, HasSubstr((dir / "x.free.csv").string()));
}

TEST(Batch, PlacementWithOneFileIsNamed) {
  testing::TempDir dir;
  dir.Write("x.stitched.csv", "id,x,y,z\n1,0,0,0\n");
  dir.Write("x.free.csv", "id,x,y,z\n1,0,0,0\n");
  dir.Write("y.free.csv", "id,x,y,z\n1,0,0,0\n");
  const std::string message = InputErrorOf([&] { ReadBatch(dir.path()); });
  EXPECT_THAT(message, HasSubstr((dir / "y.free.csv").string() + ": has no partner " +
                                 (dir / "y.stitched.csv").string()));
}

TEST(Batch, MissingOrEmptyDirectoryIsNamed) {
  testing::TempDir dir;
  EXPECT_THAT(InputErrorOf([&] { ReadBatch(dir / "absent"); }),
              HasSubstr((dir / "absent").string() + ": not a batch directory (no such directory)"));
  dir.Write("notes.txt", "not a placement");
  EXPECT_THAT(InputErrorOf([&] { ReadBatch(dir.path()); }), HasSubstr(dir.path().string() + ": no placements"));
}

TEST(Batch, BadExportInsideIsNamedWithItsLine) {
  testing::TempDir dir;
  dir.Write("x.stitched.csv", "id,x,y,z\n1,0,0,0\n6,nan,0,0\n");
  dir.Write("x.free.csv", "id,x,y,z\n1,0,0,0\n6,20,0,0\n");
  EXPECT_THAT(InputErrorOf([&] { ReadBatch(dir.path()); }),
              HasSubstr((dir / "x.stitched.csv").string() + ":3: calotte 6: x is nan"));
}

struct BadRoles {
  const char* name;
  const char* json;
  const char* what;
};
void PrintTo(const BadRoles& c, std::ostream* os) { *os << c.name; }  // names the case in test listings

class BatchBadRoles : public ::testing::TestWithParam<BadRoles> {};

TEST_P(BatchBadRoles, ThrowsNamingBatchJson) {
  testing::TempDir dir;
  for (const char* name : {"x", "y"}) {
    dir.Write(std::string(name) + ".stitched.csv", "id,x,y,z\n1,0,0,0\n");
    dir.Write(std::string(name) + ".free.csv", "id,x,y,z\n1,0,0,0\n");
  }
  dir.Write("batch.json", GetParam().json);
  const std::string message = InputErrorOf([&] { ReadBatch(dir.path()); });
  EXPECT_THAT(message, HasSubstr((dir / "batch.json").string()));
  EXPECT_THAT(message, HasSubstr(GetParam().what));
}

INSTANTIATE_TEST_SUITE_P(
    Batch, BatchBadRoles,
    ::testing::Values(BadRoles{"NotJson", "{\n  \"identify\": [\"x\",]\n}\n", "batch.json:2: not valid JSON"},
                      BadRoles{"NotAnObject", "[\"x\"]", "expected an object"},
                      BadRoles{"UnknownPlacement", R"({"identify": ["x"], "validate": ["z"]})",
                               "placement 'z' has no z.stitched.csv / z.free.csv pair here; the placements are x, y"},
                      BadRoles{"BothRoles", R"({"identify": ["x", "y"], "validate": ["y"]})",
                               "placement 'y' is both in \"identify\" and \"validate\""},
                      BadRoles{"UnknownKey", R"({"identfy": ["x"], "validate": ["y"]})", "unknown key \"identfy\""},
                      BadRoles{"NameNotString", R"({"identify": ["x", 2]})", "\"identify\" holds 2"},
                      BadRoles{"NothingToIdentify", R"({"identify": [], "validate": ["y"]})", "no placement is left"},
                      BadRoles{"LensNotString", R"({"identify": ["x"], "lens": 5})", "\"lens\" must be a string"}),
    [](const ::testing::TestParamInfo<BadRoles>& info) { return std::string(info.param.name); });

TEST(Batch, ValidateAloneLeavesTheRestToIdentify) {
  testing::TempDir dir;
  for (const char* name : {"x", "y", "z"}) {
    dir.Write(std::string(name) + ".stitched.csv", "id,x,y,z\n1,0,0,0\n");
    dir.Write(std::string(name) + ".free.csv", "id,x,y,z\n1,0,0,0\n");
  }
  dir.Write("batch.json", R"({"validate": ["y"]})");
  const Batch batch = ReadBatch(dir.path());
  EXPECT_TRUE(batch.has_roles);
  EXPECT_THAT(batch.identify, ElementsAre("x", "z"));
  EXPECT_THAT(batch.validate, ElementsAre("y"));
}

// The rules batch.json follows, for a batch given another way (Python's arrays): the messages start with `where`.
TEST(Batch, RolesOfABatchInMemoryFollowTheRulesOfBatchJson) {
  Batch batch;
  batch.placements = {MakePlacement("x", {1}, 0.0, false), MakePlacement("y", {1}, 0.0, false),
                      MakePlacement("z", {1}, 0.0, false)};
  AssignBatchRoles(batch, std::nullopt, {"y"}, "arrays");
  EXPECT_THAT(batch.identify, ElementsAre("x", "z"));
  EXPECT_THAT(batch.validate, ElementsAre("y"));
  AssignBatchRoles(batch, std::vector<std::string>{"z"}, {}, "arrays");
  EXPECT_THAT(batch.identify, ElementsAre("z"));
  EXPECT_TRUE(batch.validate.empty());
  EXPECT_THAT(InputErrorOf([&] { AssignBatchRoles(batch, std::vector<std::string>{"x"}, {"x"}, "arrays"); }),
              HasSubstr("arrays: placement 'x' is both in \"identify\" and \"validate\""));
  EXPECT_THAT(InputErrorOf([&] { AssignBatchRoles(batch, std::nullopt, {"x", "y", "z"}, "arrays"); }),
              HasSubstr("arrays: no placement is left to identify the model"));
}

TEST(Batch, FailingWriteLeavesNoFileBehind) {
  testing::TempDir dir;
  Batch batch;
  batch.placements = {MakePlacement("x", {1, 2}, 0.001, false)};
  dir.Write("blocker", "a file where the batch directory should be");
  EXPECT_THAT(InputErrorOf([&] { WriteBatch(dir / "blocker" / "batch", batch); }),
              HasSubstr((dir / "blocker" / "batch").string() + ": cannot create the batch directory"));
  EXPECT_THAT(dir.Entries(), ElementsAre("blocker"));
}

}  // namespace
}  // namespace fvm::artefacts

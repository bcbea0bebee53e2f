// fvm diff's job without the executable: per-calotte differences and distance changes of two exports, the refusals
// it makes and the summary it prints.

#include "workflows/diff.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/input_error.h"

namespace fvm::workflows {
namespace {

artefacts::CentreExport Export(const std::vector<std::pair<int, Eigen::Vector3d>>& centres) {
  artefacts::CentreExport e;
  for (const auto& [id, p] : centres) {
    artefacts::CentreRecord r;
    r.id = id;
    r.position = p;
    e.centres.push_back(r);
  }
  return e;
}

// REF: calottes 1, 2, 3 on a 10 mm grid; TEST: 1 and 2 moved by known amounts, 3 absent, 4 extra.
const artefacts::CentreExport kRef = Export({{1, {0, 0, 0}}, {2, {10, 0, 0}}, {3, {0, 10, 0}}});
const artefacts::CentreExport kTest = Export({{1, {0.001, 0, 0}}, {2, {10.004, 0, 0.003}}, {4, {5, 5, 0}}});

TEST(DiffExports, CalotteDifferencesAndDistancesOfTheCommonCalottes) {
  std::vector<std::string> warnings;
  const DiffResult r = DiffExports(kRef, kTest, {}, "ref.csv", "test.csv", [&](const std::string& w) { warnings.push_back(w); });
  ASSERT_EQ(r.calottes.size(), 2u);
  EXPECT_EQ(r.calottes[1].id, 2);
  EXPECT_NEAR(r.calottes[1].d_um.x(), 4.0, 1e-9);
  EXPECT_NEAR(r.calottes[1].d_um.z(), 3.0, 1e-9);
  EXPECT_EQ(r.only_ref, std::vector<int>{3});
  EXPECT_EQ(r.only_test, std::vector<int>{4});
  EXPECT_EQ(warnings, (std::vector<std::string>{"calotte 3 only in ref.csv; left out", "calotte 4 only in test.csv; left out"}));
  // Default pairs: the first common calotte with every other one. 3-D: sqrt(10.003^2 + 0.003^2) - 10.
  ASSERT_EQ(r.pairs.size(), 1u);
  EXPECT_NEAR(r.pairs[0].diff_um(), (std::hypot(10.003, 0.003) - 10.0) * 1e3, 1e-9);
  DiffOptions xy;
  xy.xy = true;  // in the plane the z step does not count: 3 um exactly
  EXPECT_NEAR(DiffExports(kRef, kTest, xy, "ref.csv", "test.csv").pairs[0].diff_um(), 3.0, 1e-9);
}

TEST(DiffExports, RefusesPairsOutsideBothExportsAndExportsWithNothingInCommon) {
  DiffOptions options;
  options.pairs = "1:3";
  try {
    DiffExports(kRef, kTest, options, "ref.csv", "test.csv");
    FAIL() << "calotte 3 is not in the test export";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "--pairs 1:3: calotte 3 is not in test.csv; pair calottes present in both files "
                                     "(common ids: 1, 2)");
  }
  EXPECT_THROW(DiffExports(kRef, Export({{9, {0, 0, 0}}}), {}, "ref.csv", "other.csv"), InputError);
}

TEST(DiffOptions, PairsAreTwoDifferentCalottes) {
  DiffOptions o;
  o.pairs = " 1:6 , 1:31";
  EXPECT_EQ(o.Pairs(), (std::vector<std::pair<int, int>>{{1, 6}, {1, 31}}));
  for (const std::string bad : {"1-6", "1:x", "3:3", "1:6,", "-1:2"}) {
    o.pairs = bad;
    EXPECT_THROW(o.Check(), InputError) << bad;
  }
}

TEST(DiffSummary, DocumentAndTablesFromTheResult) {
  const Summary s = Summarize(DiffExports(kRef, kTest, {}, "ref.csv", "test.csv"));
  EXPECT_EQ(s.json["distance"], "3d");
  EXPECT_EQ(s.json["calottes"][1]["dx_um"], 4.0);
  EXPECT_EQ(s.json["pairs"][0]["a"], 1);
  std::vector<std::string> keys;
  for (const auto& item : s.json.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"distance", "only_in_ref", "only_in_test", "calottes", "pairs"}));
  EXPECT_EQ(s.text,
            "REF   ref.csv\nTEST  test.csv\n\n"
            "calotte  dx [um]  dy [um]  dz [um]  |d| [um]\n"
            "      1      1.0      0.0      0.0       1.0\n"
            "      2      4.0      0.0      3.0       5.0\n"
            "\ndistances in 3-D\n"
            "pair  REF [mm]  TEST [mm]  TEST-REF [um]\n"
            " 1:2   10.0000    10.0030            3.0\n");
}

}  // namespace
}  // namespace fvm::workflows

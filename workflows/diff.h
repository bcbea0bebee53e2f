#pragma once
// How far a test export of an artefact is from a reference export of it (`fvm diff`), calotte by calotte and as
// distances between calottes: the measure of the published stitching-strategy study ([Pérez 2019] Tables 1-2).

#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "artefacts/io/centre_export.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct DiffOptions {
  std::string pairs;  // "a:b[,a:b...]"; empty: the first common calotte with every other one
  bool xy = false;    // distances in the XY plane, z ignored

  // Throws InputError naming --pairs for a pair that is not two different calotte ids.
  void Check() const;
  std::vector<std::pair<int, int>> Pairs() const;  // the pairs --pairs names (checked)
};

struct CalotteDiff {
  int id = 0;
  Eigen::Vector3d d_um = Eigen::Vector3d::Zero();  // TEST - REF
};

struct PairDiff {
  int a = 0, b = 0;
  double ref_mm = 0.0, test_mm = 0.0;
  double diff_um() const { return (test_mm - ref_mm) * 1000.0; }
};

struct DiffResult {
  std::string ref, test;  // the exports' names (their files)
  bool xy = false;
  std::vector<int> only_ref, only_test;  // calottes left out
  std::vector<CalotteDiff> calottes;     // the common calottes, in REF's order
  std::vector<PairDiff> pairs;
};

// The differences of two exports named `ref_name` and `test_name` (in messages). `warn` hears of calottes in one
// export only (left out) before anything is refused. Throws InputError when the exports share no calotte or a pair
// names a calotte not in both.
DiffResult DiffExports(const artefacts::CentreExport& ref, const artefacts::CentreExport& test,
                       const DiffOptions& options, const std::string& ref_name, const std::string& test_name,
                       const std::function<void(const std::string&)>& warn = {});
// The same for two centre-export files.
DiffResult DiffFiles(const std::string& ref, const std::string& test, const DiffOptions& options,
                     const std::function<void(const std::string&)>& warn = {});

// The --json document {"distance", "only_in_ref", "only_in_test", "calottes", "pairs"} (the command adds "ref" and
// "test" first) and the two tables the command prints.
Summary Summarize(const DiffResult& result);

}  // namespace fvm::workflows

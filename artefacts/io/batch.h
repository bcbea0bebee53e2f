#pragma once
// A batch directory: pairs <placement>.stitched.csv / <placement>.free.csv of the same calottes, and an optional
// batch.json {"identify": [...], "validate": [...], "lens": "5x"} (README, "The main job").

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/centre_export.h"

namespace fvm::artefacts {

struct Placement {
  std::string name;
  std::vector<int> ids;                    // the calottes, in the stitched file's order
  std::vector<Eigen::Vector3d> stitched;   // reference (stitched) centres, mm, in ids order
  std::vector<Eigen::Vector3d> free;       // stitching-free centres, mm, in ids order
  std::vector<double> t_s;                 // time of each stitching-free centre when the export has t, else empty
};

struct Batch {
  std::filesystem::path dir;
  std::vector<Placement> placements;  // sorted by name
  bool has_roles = false;             // batch.json present
  std::vector<std::string> identify;  // placement names (all of them when there is no batch.json)
  std::vector<std::string> validate;  // placement names (empty when there is no batch.json)
  std::string lens;                   // from batch.json, may be empty

  const Placement& Get(const std::string& name) const;  // throws InputError when absent
};

// Throws InputError naming the file and calotte id on: a missing or empty directory, a placement with only one
// of its two files, ids present in one file of a pair and not the other, unreadable exports (see
// ReadCentreExport), an export whose calottes span less than 10 um in x and y (they cannot show a stage error), a
// batch.json that is not JSON (or nests deeper than 64 levels), names an unknown placement, or puts one in both roles.
Batch ReadBatch(const std::filesystem::path& dir);

// One placement from its two centre exports (messages name their `source`): the stitched export defines the
// calottes and their order; throws InputError naming the file, line and calotte id when the free export does not
// hold exactly the same calottes, and naming the file when either export's calottes span less than 10 um in x and y.
Placement PairCentreExports(const std::string& name, const CentreExport& stitched, const CentreExport& free);

// Gives batch.placements their roles: from dir/batch.json when it exists (throws as ReadBatch on a bad one), else
// every placement identifies. ReadBatch calls it; so does a reader of raw exports (raw_export_batch.h).
void ApplyBatchRoles(const std::filesystem::path& dir, Batch& batch);

// The role rules, for batch.json and a script's lists alike: `identify` when given, else every placement not in
// `validate`. Throws InputError starting with `where` for a placement the batch lacks, one in both roles (validation
// data never enters the fit), or no placement left to identify. Sets batch.identify and batch.validate.
void AssignBatchRoles(Batch& batch, std::optional<std::vector<std::string>> identify, std::vector<std::string> validate,
                      const std::string& where);

// Writes a batch (pairs and, when roles are given, batch.json) atomically file by file.
void WriteBatch(const std::filesystem::path& dir, const Batch& batch);

}  // namespace fvm::artefacts

// A batch of raw exports (artefacts/io/raw_export_batch.h) on surfaces rendered by the simulator
// (artefacts/simulation/raw_export_simulation.h): the centres found against the exact ones the surfaces were
// rendered from, both routes ending in the same Batch, and the refusals naming the calotte ids.

#include "artefacts/io/raw_export_batch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/raw_export_simulation.h"
#include "imaging/io/surface_file.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::HasSubstr;

// The three identification placements (X, Y, oblique), surfaces at 0.1 mm with 2 um of height noise.
SimulatedFvmBatch Simulated() {
  FvmBatchOptions options;
  options.seed = 11;
  options.validation_placements = 0;
  return SimulateFvmBatch(options);
}

RawExportSimulationOptions Surfaces() {
  RawExportSimulationOptions options;
  options.pixel_mm = 0.1;
  options.noise_um = 2.0;
  return options;
}

void WriteSurfaces(const std::filesystem::path& dir, const Batch& exact) {
  for (size_t i = 0; i < exact.placements.size(); ++i) {
    const RawExportPair maps = RenderRawExports(exact.placements[i], i, Surfaces());
    imaging::WriteHeightMap(dir / (exact.placements[i].name + ".stitched.x3p"), maps.stitched);
    imaging::WriteHeightMap(dir / (exact.placements[i].name + ".free.x3p"), maps.free);
  }
}

TEST(RawExportBatch, FindsEveryCalotteWhereTheSurfaceWasRendered) {
  const SimulatedFvmBatch sim = Simulated();
  TempDir dir;
  WriteSurfaces(dir.path(), sim.exact);
  ASSERT_TRUE(HoldsRawExports(dir.path()));
  const RawExportBatch raw = ReadRawExportBatch(dir.path());
  ASSERT_EQ(raw.batch.placements.size(), 3u);
  EXPECT_EQ(raw.batch.identify.size(), 3u);  // no batch.json: every placement identifies
  EXPECT_EQ(raw.fits.size(), 6u);
  for (const Placement& found : raw.batch.placements) {
    const Placement& exact = sim.exact.Get(found.name);
    ASSERT_EQ(found.ids.size(), 17u) << found.name;
    // ~290 points of 2 um noise per calotte: a centre to about 0.3 um (x, y) and 0.2 um (z); 2 um is > 6 sigma.
    // The ids may run backwards along a bar measured along y (either numbering pairs the exports); compare each
    // found calotte with the exact one nearest it, and the pairing of the two exports through the same id.
    for (size_t k = 0; k < found.ids.size(); ++k) {
      size_t nearest = 0;
      for (size_t j = 1; j < exact.ids.size(); ++j) {
        if ((exact.stitched[j] - found.stitched[k]).norm() < (exact.stitched[nearest] - found.stitched[k]).norm()) {
          nearest = j;
        }
      }
      EXPECT_LT((exact.stitched[nearest] - found.stitched[k]).norm() * 1e3, 2.0)
          << found.name << " calotte " << found.ids[k] << " (stitched)";
      EXPECT_LT((exact.free[nearest] - found.free[k]).norm() * 1e3, 2.0)
          << found.name << " calotte " << found.ids[k] << " (free, paired through the id)";
    }
  }
  // The centres written as a CSV batch read back as the same Batch.
  TempDir centres;
  WriteRawExportCentres(centres.path(), raw);
  const Batch again = ReadBatch(centres.path());
  ASSERT_EQ(again.placements.size(), raw.batch.placements.size());
  for (size_t p = 0; p < again.placements.size(); ++p) {
    EXPECT_EQ(again.placements[p].ids, raw.batch.placements[p].ids);
    for (size_t k = 0; k < again.placements[p].ids.size(); ++k) {
      EXPECT_LT((again.placements[p].free[k] - raw.batch.placements[p].free[k]).norm(), 1e-6);
    }
  }
}

TEST(RawExportBatch, RefusesExportsThatDoNotNumberTheSameCalottes) {
  SimulatedFvmBatch sim = Simulated();
  TempDir dir;
  WriteSurfaces(dir.path(), sim.exact);
  // id-x's stitching-free surface without calotte 9.
  Placement without = sim.exact.Get("id-x");
  without.ids.erase(without.ids.begin() + 8);
  without.stitched.erase(without.stitched.begin() + 8);
  without.free.erase(without.free.begin() + 8);
  imaging::WriteHeightMap(dir.path() / "id-x.free.x3p", RenderRawExports(without, 0, Surfaces()).free);
  const std::string message = InputErrorOf([&] { ReadRawExportBatch(dir.path()); });
  EXPECT_THAT(message, HasSubstr("placement id-x: the two exports do not number the same calottes: calotte 9 found in"));
  EXPECT_THAT(message, HasSubstr("id-x.stitched.x3p but not in"));
}

TEST(RawExportBatch, RefusesASurfaceWithoutItsStagePositionAndAMissingPartner) {
  const SimulatedFvmBatch sim = Simulated();
  TempDir dir;
  RawExportPair maps = RenderRawExports(sim.exact.placements[0], 0, Surfaces());
  maps.free.x0_mm = maps.free.y0_mm = 0.0;
  imaging::WriteHeightMap(dir.path() / "a.stitched.x3p", maps.stitched);
  imaging::WriteHeightMap(dir.path() / "a.free.x3p", maps.free);
  EXPECT_THAT(InputErrorOf([&] { ReadRawExportBatch(dir.path()); }), HasSubstr("a.free.x3p: the surface starts at (0, 0) mm"));
  std::filesystem::remove(dir.path() / "a.free.x3p");
  EXPECT_THAT(InputErrorOf([&] { ReadRawExportBatch(dir.path()); }), HasSubstr("a.stitched.x3p: has no partner"));
}

}  // namespace
}  // namespace fvm::artefacts

// Registration of real camera tiles judged without a truth (issue 30): the strip of ../shared/realdata/tiles/
// starrynight, a printed grid with hand-written numbers whose steps range 242-358 px for a nominal 297, against
// the positions Fiji's Grid/Collection stitching registered. The measure is the normalised cross-correlation of
// each neighbour pair's overlap at the positions (imaging/overlap_correlation.h). Skipped where ../shared is absent.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "imaging/overlap_correlation.h"
#include "tests/support/starrynight_strip.h"

namespace fvm::imaging {
namespace {

TEST(RealTileStrip, OverlapCorrelationIsTheMeasure) {
  const testing::RealStrip strip = testing::LoadStarrynight();
  if (strip.images.empty()) GTEST_SKIP() << "../shared/realdata absent";
  // An independent check of OverlapNcc: the overlap of tiles 1 and 2 at Fiji's offset, summed here directly.
  const Eigen::Vector2d offset = strip.fiji_px[1] - strip.fiji_px[0];
  const auto ox = static_cast<int>(offset.x()), oy = static_cast<int>(offset.y());
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
  for (int y = std::max(0, oy); y < std::min(929, 929 + oy); ++y) {
    for (int x = std::max(0, ox); x < std::min(594, 594 + ox); ++x) {
      const double a = strip.images[0](y, x), b = strip.images[1](y - oy, x - ox);
      sa += a, sb += b, saa += a * a, sbb += b * b, sab += a * b, n += 1;
    }
  }
  const double direct = (sab / n - sa / n * sb / n) / std::sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
  const OverlapCorrelation measured = OverlapNcc(strip.images[0], strip.images[1], offset);
  EXPECT_NEAR(measured.ncc, direct, 1e-9);
  EXPECT_EQ(measured.pixels, static_cast<int>(n));
  // A tenth of a pixel off resamples b bilinearly: the correlation moves by little.
  EXPECT_NEAR(OverlapNcc(strip.images[0], strip.images[1], offset + Eigen::Vector2d(0.1, 0.1)).ncc, direct, 0.02);
}

TEST(RealTileStrip, RegistersEveryPairAsWellAsFiji) {
  const testing::RealStrip strip = testing::LoadStarrynight();
  if (strip.images.empty()) GTEST_SKIP() << "../shared/realdata absent";
  const RegistrationResult result = RegisterTileGrid(strip.images, strip.tiles, RegistrationOptions{});
  const auto fiji = NeighbourOverlapNcc(strip.images, strip.tiles, strip.fiji_px);
  const auto ours = NeighbourOverlapNcc(strip.images, strip.tiles, result.positions.positions_px);
  ASSERT_EQ(fiji.size(), 9u);
  ASSERT_EQ(ours.size(), 9u);
  double fiji_mean = 0.0, ours_mean = 0.0;
  int accepted = 0;
  for (size_t k = 0; k < 9; ++k) {
    const PairRegistration& pair = result.pairs[k];
    accepted += pair.accepted;
    fiji_mean += fiji[k].correlation.ncc / 9.0;
    ours_mean += ours[k].correlation.ncc / 9.0;
    const Eigen::Vector2d step = result.positions.positions_px[k + 1] - result.positions.positions_px[k];
    const Eigen::Vector2d fiji_step = strip.fiji_px[k + 1] - strip.fiji_px[k];
    std::printf("%zu-%zu: fvm step %7.2f %6.2f ncc %.3f%s | Fiji %7.1f %5.1f ncc %.3f\n", k + 1, k + 2, step.x(),
                step.y(), ours[k].correlation.ncc, pair.ambiguous ? " (ambiguous)" : "", fiji_step.x(), fiji_step.y(),
                fiji[k].correlation.ncc);
    EXPECT_TRUE(pair.accepted) << k + 1 << "-" << k + 2 << ": " << pair.rejection;
  }
  std::printf("mean overlap ncc: fvm %.4f, Fiji %.4f; %d of 9 pairs\n", ours_mean, fiji_mean, accepted);
  EXPECT_EQ(accepted, 9);
  // The goal: a mean at least Fiji's, and no pair below 0.3 where Fiji's is above 0.5. Measured 0.788
  // against 0.744 (before the search over the whole plausible range: 0.598, the steps of 242-245 px taken for
  // ~300-330 px); every pair at least Fiji's less 0.01 (the bilinear resampling of fvm's sub-pixel offsets reads a
  // noisy overlap up to a few hundredths low).
  EXPECT_GE(ours_mean, fiji_mean);
  int within_2px = 0;
  for (size_t k = 0; k < 9; ++k) {
    EXPECT_GE(ours[k].correlation.ncc, fiji[k].correlation.ncc - 0.01) << k + 1 << "-" << k + 2;
    if (fiji[k].correlation.ncc > 0.5) {
      EXPECT_GT(ours[k].correlation.ncc, 0.3) << k + 1 << "-" << k + 2;
    }
    const Eigen::Vector2d step = result.positions.positions_px[k + 1] - result.positions.positions_px[k];
    const double off = (step - (strip.fiji_px[k + 1] - strip.fiji_px[k])).cwiseAbs().maxCoeff();
    within_2px += off <= 2.0;
    // Where Fiji's overlap correlates well (above 0.7: all but 7-8), the steps agree within 4 px: the real tiles
    // are no pure translation of each other (their best offsets move by pixels with the band they are judged
    // in), and Fiji's positions are whole pixels. At 7-8 (Fiji 0.52) fvm steps 353.6 px where Fiji steps 334, and
    // its overlap correlates 0.66.
    if (fiji[k].correlation.ncc > 0.7) {
      EXPECT_LE(off, 4.0) << k + 1 << "-" << k + 2;
    }
  }
  // Measured 5 of 9 (1-2 and 5-6 differ by 2.9 and 3.7 px in y, 9-10 by 2.2 px in x, 7-8 as above).
  EXPECT_GE(within_2px, 5);
  // Fiji's own positions are the reference of the measure: every one of its overlaps correlates above 0.5.
  for (const auto& f : fiji) EXPECT_GT(f.correlation.ncc, 0.5) << f.a + 1 << "-" << f.b + 1;
}

}  // namespace
}  // namespace fvm::imaging

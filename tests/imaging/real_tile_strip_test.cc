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

// The NCC of the values as stored, summed here directly, over the rows [y0, y1) of a's frame that the overlap holds
// when b's top-left lies at the whole pixel o in a's frame; `pixels` counts them.
double DirectNcc(const TileImage& a, const TileImage& b, const Eigen::Vector2i& o, int y0, int y1, int& pixels) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
  for (int y = std::max({0, o.y(), y0}); y < std::min({929, 929 + o.y(), y1}); ++y) {
    for (int x = std::max(0, o.x()); x < std::min(594, 594 + o.x()); ++x) {
      const double va = a(y, x), vb = b(y - o.y(), x - o.x());
      sa += va, sb += vb, saa += va * va, sbb += vb * vb, sab += va * vb, n += 1;
    }
  }
  pixels = static_cast<int>(n);
  return (sab / n - sa / n * sb / n) / std::sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
}

TEST(RealTileStrip, OverlapCorrelationIsTheMeasure) {
  const testing::RealStrip strip = testing::LoadStarrynight();
  if (strip.images.empty()) GTEST_SKIP() << "../shared/realdata absent";
  // An independent check of OverlapNcc: the overlap of tiles 1 and 2 at Fiji's offset, summed here directly.
  const Eigen::Vector2d offset = strip.fiji_px[1] - strip.fiji_px[0];
  int n = 0;
  const double direct = DirectNcc(strip.images[0], strip.images[1], offset.cast<int>(), 0, 929, n);
  const OverlapCorrelation measured = OverlapNcc(strip.images[0], strip.images[1], offset);
  EXPECT_NEAR(measured.ncc, direct, 1e-9);
  EXPECT_EQ(measured.pixels, n);
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
  // The goal: a mean at least Fiji's, and no pair below 0.3 where Fiji's is above 0.5. Measured 0.785
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
    // in), and Fiji's positions are whole pixels. At 7-8 (Fiji 0.52) fvm steps 352.8 px where Fiji steps 334, and
    // its overlap correlates 0.65.
    if (fiji[k].correlation.ncc > 0.7) {
      EXPECT_LE(off, 4.0) << k + 1 << "-" << k + 2;
    }
  }
  // Measured 5 of 9: 1-2 differs by 3.0 px in y, 5-6 by 2.3 and 9-10 by 2.2 px in x, 7-8 as above
  // (FijiMatchesWorseInEveryThirdOfTheOverlap).
  EXPECT_GE(within_2px, 5);
  // Fiji's own positions are the reference of the measure: every one of its overlaps correlates above 0.5.
  for (const auto& f : fiji) EXPECT_GT(f.correlation.ncc, 0.5) << f.a + 1 << "-" << f.b + 1;
}

// Where fvm's and Fiji's steps differ most (1-2 by 3 px in y, 7-8 by 19 px in x), which is right? Fiji's
// positions are whole pixels and its nine steps chain its nine pairs exactly (a strip has no loop for a global
// placement to average), so each of its steps is its own pair's answer. The values as stored are judged in each third of the
// overlap (top, middle, bottom) on its own, at whole pixels, so that neither resampling nor a turn of the tiles
// (their best steps move by pixels from top to bottom: 5-6 from -4 to -8 px in y) favours one side: at fvm's step
// every third matches better than at Fiji's. Overlays of 7-8 (tile 7 red, tile 8 cyan) show why: at 353 px the
// grid's vertical line in the overlap lies on itself, at 334 px it is doubled, red and cyan some 19 px apart.
TEST(RealTileStrip, FijiMatchesWorseInEveryThirdOfTheOverlap) {
  const testing::RealStrip strip = testing::LoadStarrynight();
  if (strip.images.empty()) GTEST_SKIP() << "../shared/realdata absent";
  const RegistrationResult result = RegisterTileGrid(strip.images, strip.tiles, RegistrationOptions{});
  const auto third = [&](size_t k, const Eigen::Vector2i& o, int band) {
    int pixels = 0;
    return DirectNcc(strip.images[k], strip.images[k + 1], o, band * 310, band * 310 + 310, pixels);
  };
  for (const size_t k : {0u, 6u}) {
    const Eigen::Vector2i ours = (result.positions.positions_px[k + 1] - result.positions.positions_px[k]).array().round().cast<int>();
    const Eigen::Vector2i fiji = (strip.fiji_px[k + 1] - strip.fiji_px[k]).array().round().cast<int>();
    for (int band = 0; band < 3; ++band) {
      std::printf("%zu-%zu third %d: fvm (%d, %d) %.3f, Fiji (%d, %d) %.3f\n", k + 1, k + 2, band, ours.x(), ours.y(),
                  third(k, ours, band), fiji.x(), fiji.y(), third(k, fiji, band));
      EXPECT_GT(third(k, ours, band), third(k, fiji, band)) << k + 1 << "-" << k + 2 << " third " << band;
    }
  }
}

}  // namespace
}  // namespace fvm::imaging

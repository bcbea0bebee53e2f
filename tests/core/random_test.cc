// core/random.h claims the same bits with any standard library: the engine is the one the C++ standard specifies
// to the bit, and the uniform and normal values come from our own arithmetic. These tests hold it to that.

#include "core/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <set>

namespace fvm {
namespace {

// [rand.predef]: the 10000th output of a default-constructed std::mt19937_64 is 9981545732273789042. Uniform()
// keeps its top 53 bits, so the 10000th uniform of seed 5489 (the default seed) is that number over 2^64, cut.
TEST(Random, UniformIsTheStandardEngineCutTo53Bits) {
  Random random(std::mt19937_64::default_seed);
  for (int i = 1; i < 10000; ++i) random.Uniform();
  EXPECT_EQ(random.Uniform(), static_cast<double>(9981545732273789042ULL >> 11) * 0x1.0p-53);
}

// Box-Muller on two uniforms, written out here from the engine's own outputs: one normal per pair of draws.
TEST(Random, NormalIsBoxMullerOfTwoUniforms) {
  std::mt19937_64 engine(7);
  Random random(7);
  for (int i = 0; i < 100; ++i) {
    const double u1 = 1.0 - static_cast<double>(engine() >> 11) * 0x1.0p-53;
    const double u2 = static_cast<double>(engine() >> 11) * 0x1.0p-53;
    ASSERT_EQ(random.Normal(), std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2)) << "draw " << i;
  }
}

// The first normals of seed 1 as glibc's libm gives them: a change of arithmetic (another distribution, another
// order of draws) changes these bits and every recorded truth of the simulators with them.
TEST(Random, NormalsOfSeedOneKeepTheirBits) {
  Random random(1);
  EXPECT_EQ(random.Normal(), 0x1.676a93ccea5p-2);
  EXPECT_EQ(random.Normal(), 0x1.16007c53e018dp+0);
  EXPECT_EQ(random.Normal(), 0x1.94108d1f8799fp-1);
}

// 200 000 normals: mean within 5 standard errors of 0, variance within 5 of 1 (the variance of s^2 is 2/n).
TEST(Random, NormalHasUnitVariance) {
  Random random(3);
  const int n = 200000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = random.Normal();
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / n, variance = sum2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 5.0 / std::sqrt(n));
  EXPECT_NEAR(variance, 1.0, 5.0 * std::sqrt(2.0 / n));
}

// Stream seeds are pure integer arithmetic (SplitMix64's finaliser): fixed values, and distinct streams.
TEST(Random, StreamSeedsAreFixedAndDistinct) {
  EXPECT_EQ(StreamSeed(0, 0), 0xa706dd2f4d197e6fULL);
  EXPECT_EQ(StreamSeed(1, 0), 0x5e41ab087439611eULL);
  EXPECT_EQ(StreamSeed(1, 1), 0xe9fd6049d65af21eULL);
  std::set<std::uint64_t> seen;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    for (std::uint64_t index = 0; index < 1000; ++index) seen.insert(StreamSeed(seed, index));
  }
  EXPECT_EQ(seen.size(), 20000u);
}

// The SplitMix64 sequence of a seed (fvm simulate tracker's parts): its reference outputs (0x910a2dec89025cc1 is
// splitmix64's first number from seed 1 in Vigna's reference code), the same bits as the simulator drew before
// the seeds moved to core.
TEST(Random, SequenceSeedsAreSplitMix64sSequence) {
  EXPECT_EQ(SplitMix64(1), 0x910a2dec89025cc1ULL);
  EXPECT_EQ(SequenceSeed(1, 0), 0x910a2dec89025cc1ULL);
  EXPECT_EQ(SequenceSeed(1, 2), 0xf893a2eefb32555eULL);
  EXPECT_NE(SequenceSeed(1, 1), StreamSeed(1, 1));
}

}  // namespace
}  // namespace fvm

// The peak fit's phase bias (imaging/focus_phase_bias.h) on synthetic height maps: a tilted face whose heights
// carry a known periodic function of their phase between the images plus noise (recovered within its noise and
// taken off), the same face without the bias (nothing invented), and a face level within a step (declined); and the
// bias predicted from a focus curve's rises where it cannot be measured.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "imaging/focus_peak.h"
#include "imaging/focus_phase_bias.h"

namespace fvm {
namespace {

constexpr int kSide = 256;
constexpr double kStep = 1e-3, kOrigin = 0.37e-3;  // mm
constexpr double kNoiseSteps = 0.02;

// A face tilted by `tilt_x`, `tilt_y` steps per px (3 and 1.8 steps over the map at 0.012 and -0.007), with
// `bias(phase)` steps added and Gaussian noise; NaN in a band of holes.
struct Face {
  std::vector<double> truth, z;
  std::vector<float> slope_x, slope_y;
  imaging::PhaseBiasInput in;

  template <class Bias>
  Face(double tilt_x, double tilt_y, Bias bias, unsigned seed, double noise_steps = kNoiseSteps) {
    std::mt19937 random(seed);
    std::normal_distribution<double> noise(0.0, noise_steps);
    const std::size_t n = std::size_t(kSide) * kSide;
    truth.resize(n), z.resize(n);
    slope_x.assign(n, float(tilt_x * kStep)), slope_y.assign(n, float(tilt_y * kStep));
    for (int r = 0; r < kSide; ++r) {
      for (int c = 0; c < kSide; ++c) {
        const std::size_t i = std::size_t(r) * kSide + std::size_t(c);
        const double steps = 5.2 + tilt_x * c + tilt_y * r;  // from the first image
        truth[i] = kOrigin + steps * kStep;
        const double phase = steps - std::round(steps);
        z[i] = (r > 100 && r < 104) ? std::nan("") : truth[i] + (bias(phase) + noise(random)) * kStep;
      }
    }
    in.width = kSide, in.height = kSide, in.z_mm = &z;
    in.slope_x = slope_x.data(), in.slope_y = slope_y.data();
    in.origin_mm = kOrigin, in.step_mm = kStep;
  }

  double RmsError() const {
    double sum = 0.0;
    int count = 0;
    for (std::size_t i = 0; i < z.size(); ++i) {
      if (std::isfinite(z[i])) sum += (z[i] - truth[i]) * (z[i] - truth[i]), ++count;
    }
    return std::sqrt(sum / count) / kStep;
  }
};

double KnownBias(double phase) {
  return 0.04 * std::sin(2.0 * std::numbers::pi * phase) + 0.012 * std::cos(4.0 * std::numbers::pi * phase);
}

TEST(FocusPhaseBias, RecoversAKnownPeriodicBiasWithinItsNoiseAndTakesItOff) {
  Face face(0.012, -0.007, KnownBias, 3);
  const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
  ASSERT_TRUE(bias.applied) << bias.reason;
  EXPECT_GT(bias.shrinkage, 0.95);  // a bias 20 times its noise is hardly shrunk
  for (double phase = -0.5; phase < 0.5; phase += 0.0625) {
    // The fit is a function of the measured heights' phase, which the bias itself has moved.
    const double measured = phase + KnownBias(phase);
    const double found = bias.At(measured) / kStep, u = bias.Uncertainty(measured) / kStep;
    EXPECT_GT(u, 0.0);
    EXPECT_LT(u, 0.005);  // 60000 points of 0.02 step noise
    // Within 4 u plus the blur of the noise (0.02 step of noise moves a phase by 0.02, where the bias changes by at
    // most 0.25 times that).
    EXPECT_NEAR(found, KnownBias(phase), 4.0 * u + 0.005) << "phase " << phase;
  }
  const double before = face.RmsError();
  std::vector<float> u;
  imaging::CorrectPhaseBias(bias, face.in, face.z, u);
  const double after = face.RmsError();
  EXPECT_GT(before, 0.03);
  EXPECT_LT(after, 0.024);  // the noise (0.02 step) and what the fit leaves
  // Where nothing is known the holes stay holes; elsewhere the correction has an uncertainty.
  EXPECT_TRUE(std::isnan(face.z[std::size_t(102) * kSide + 5]));
  EXPECT_GT(u[5], 0.0f);
  // The level points' scatter about their planes is the noise, once the bias is off.
  EXPECT_NEAR(bias.LevelScatter(50, 50) / kStep, after, 0.004) << after;
}

// The heights' local mean (mm from the origin) over a box of `half` px either side, valid points only: where a
// pixel's phase is read from when its own height errs by a sizeable share of a step.
std::vector<float> LocalMeanHeights(const Face& face, int half) {
  std::vector<float> mean(face.z.size());
  for (int r = 0; r < kSide; ++r) {
    for (int c = 0; c < kSide; ++c) {
      double sum = 0.0;
      int count = 0;
      for (int i = std::max(0, r - half); i <= std::min(kSide - 1, r + half); ++i) {
        for (int j = std::max(0, c - half); j <= std::min(kSide - 1, c + half); ++j) {
          const double z = face.z[std::size_t(i) * kSide + std::size_t(j)];
          if (std::isfinite(z)) sum += z - kOrigin, ++count;
        }
      }
      mean[std::size_t(r) * kSide + std::size_t(c)] = count > 0 ? float(sum / count) : 0.0f;
    }
  }
  return mean;
}

TEST(FocusPhaseBias, RecoversTheWholeBiasUnderNoisyHeightsFromThePhaseOfTheirLocalMean) {
  // Heights that err by 0.1 step (NA 0.9 with a 0.8 um floor on focusgen.py). Read from each height, the phase
  // carries that error: the harmonics of a noisy phase shrink (errors in the regressor), and the noise itself
  // correlates with them, since the bias makes the heights' phases crowd where it pulls them (their density is
  // 1 / (1 + bias'), here +-57 %) and a noisy phase lies, on average, towards where they crowd. Here the fit so
  // read finds 0.011 of the 0.067 step rms. Read from the local mean of 13 x 13 heights (0.008 step of noise), the
  // whole bias is found.
  const auto bias_of = [](double phase) {
    return 0.09 * std::sin(2.0 * std::numbers::pi * phase) + 0.03 * std::cos(4.0 * std::numbers::pi * phase);
  };
  const double truth = std::sqrt(0.5 * 0.09 * 0.09 + 0.5 * 0.03 * 0.03);  // 0.067 step
  Face face(0.012, -0.007, bias_of, 7, 0.1);
  const imaging::PhaseBias own = imaging::EstimatePhaseBias(face.in);
  const std::vector<float> mean = LocalMeanHeights(face, 6);
  face.in.phase_heights = mean.data();
  const imaging::PhaseBias smoothed = imaging::EstimatePhaseBias(face.in);
  ASSERT_TRUE(own.applied) << own.reason;
  ASSERT_TRUE(smoothed.applied) << smoothed.reason;
  // The fit's noise: 60000 points of 0.1 step leave about 0.001 step on each coefficient; 5 % of the truth holds
  // that and the three harmonics' truncation of the bias seen through the smoothed phase.
  EXPECT_NEAR(smoothed.Rms() / kStep, truth, 0.05 * truth);
  EXPECT_LT(own.Rms() / kStep, 0.5 * truth);  // the dilution this input exists to avoid
  const double before = face.RmsError();
  std::vector<float> u;
  imaging::CorrectPhaseBias(smoothed, face.in, face.z, u);
  // What is left is the noise (0.1 step) and what the fit leaves: the bias (0.067 step) is gone.
  EXPECT_GT(before, 0.118);
  EXPECT_LT(face.RmsError(), 0.102);
  std::printf("bias rms %.4f step: from the local mean's phase %.4f, from each height's %.4f; heights %.4f -> %.4f\n",
              truth, smoothed.Rms() / kStep, own.Rms() / kStep, before, face.RmsError());
}

TEST(FocusPhaseBias, InventsNoBiasOnAFaceWithout) {
  Face face(0.012, -0.007, [](double) { return 0.0; }, 4);
  const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
  for (double phase = -0.5; phase < 0.5; phase += 0.0625) {
    EXPECT_LT(std::abs(bias.At(phase)) / kStep, 0.004) << "phase " << phase;
  }
}

// Gaussian noise of `rms_steps` (mm in the map: steps times kStep) smoothed over `sigma_px` (a Gaussian kernel run
// along the rows, then the columns): errors shared by neighbours, as a focus window's are.
std::vector<double> CorrelatedNoise(unsigned seed, double sigma_px, double rms_steps) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int reach = int(std::ceil(3.0 * sigma_px)), side = kSide + 2 * reach;
  std::vector<double> kernel(std::size_t(2 * reach + 1));
  for (int k = -reach; k <= reach; ++k) kernel[std::size_t(k + reach)] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
  std::vector<double> white(std::size_t(side) * side), rows(std::size_t(side) * kSide), out(std::size_t(kSide) * kSide);
  for (double& w : white) w = normal(random);
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < kSide; ++c) {
      double sum = 0.0;
      for (int k = -reach; k <= reach; ++k)
        sum += kernel[std::size_t(k + reach)] * white[std::size_t(r) * side + std::size_t(c + reach + k)];
      rows[std::size_t(r) * kSide + std::size_t(c)] = sum;
    }
  }
  double square = 0.0;
  for (int r = 0; r < kSide; ++r) {
    for (int c = 0; c < kSide; ++c) {
      double sum = 0.0;
      for (int k = -reach; k <= reach; ++k)
        sum += kernel[std::size_t(k + reach)] * rows[std::size_t(r + reach + k) * kSide + std::size_t(c)];
      out[std::size_t(r) * kSide + std::size_t(c)] = sum, square += sum * sum;
    }
  }
  const double scale = rms_steps * kStep / std::sqrt(square / double(out.size()));
  for (double& v : out) v *= scale;
  return out;
}

TEST(FocusPhaseBias, ItsUncertaintyCoversItsErrorUnderErrorsSharedOverManyPixels) {
  // Heights whose errors correlate over about 10 px (0.5 at 10 px: noise smoothed by a Gaussian of 6 px; the
  // heights of focusgen.py's stacks correlate 0.5 at about 8 px, farther at a 2 px texture or NA 0.9 with a 0.8 um
  // floor): the blocks of 16 px the sandwich sums its scores over share errors across their borders, and the
  // sandwich over them alone said 0.76 of the error (error / u rms 1.32 over these 24 faces; 1.15 with the wide
  // blocks' too). The error / u rms must be within the 0.8-1.25 that judges any uncertainty; the phase is read
  // from the true heights, so that only the estimate's own error is judged.
  double square = 0.0;
  int count = 0;
  for (unsigned seed = 100; seed < 124; ++seed) {
    Face face(0.012, -0.007, KnownBias, seed, 0.005);
    const std::vector<double> noise = CorrelatedNoise(seed, 6.0, 0.03);
    std::vector<float> truth(face.z.size());
    for (std::size_t i = 0; i < face.z.size(); ++i) {
      face.z[i] += noise[i];
      truth[i] = float(face.truth[i] - kOrigin);
    }
    face.in.phase_heights = truth.data();
    const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
    ASSERT_TRUE(bias.applied) << bias.reason;
    for (double phase = -0.5; phase < 0.5; phase += 0.0625) {
      const double error = (bias.At(phase) / kStep - KnownBias(phase)) / (bias.Uncertainty(phase) / kStep);
      square += error * error, ++count;
    }
  }
  const double rms = std::sqrt(square / count);
  EXPECT_GT(rms, 0.8);
  EXPECT_LT(rms, 1.25);
  std::printf("error / u of the phase bias under errors correlated over 10 px: rms %.2f over %d phases\n", rms, count);
}

TEST(FocusPhaseBias, DeclinesOnAFaceLevelWithinAStep) {
  // 0.2 step over the whole map: the phases are the face's one phase plus noise.
  Face face(0.0005, 0.0003, KnownBias, 5);
  const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
  EXPECT_FALSE(bias.applied);
  EXPECT_NE(bias.reason.find("phases"), std::string::npos) << bias.reason;
  const std::vector<double> before = face.z;
  std::vector<float> u;
  imaging::CorrectPhaseBias(bias, face.in, face.z, u);
  for (std::size_t i = 0; i < before.size(); i += 97) {
    if (std::isfinite(before[i])) {
      EXPECT_EQ(face.z[i], before[i]);
      EXPECT_EQ(u[i], 0.0f);
    }
  }
}

TEST(FocusPhaseBias, DeclinesWithTooFewLevelPoints) {
  // Slopes of 0.2 step per px everywhere: a wall, not a face.
  Face face(0.2, 0.0, KnownBias, 6);
  const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
  EXPECT_FALSE(bias.applied);
  EXPECT_NE(bias.reason.find("level points"), std::string::npos) << bias.reason;
}

TEST(FocusPhaseBias, DeclinesOnAnUnevenlySteppedStack) {
  // The face that carries a bias the fit recovers, but from a stack whose images are not evenly stepped: the phase
  // read against an even grid would be wrong by up to the unevenness.
  Face face(0.012, -0.007, KnownBias, 3);
  face.in.uneven_steps = 0.3;
  const imaging::PhaseBias bias = imaging::EstimatePhaseBias(face.in);
  EXPECT_FALSE(bias.applied);
  EXPECT_NE(bias.reason.find("uneven"), std::string::npos) << bias.reason;
}

// A stack's focus curves as the modified Laplacian sees them: f ~ s^-3 for a blur of width s (u in steps from the
// surface). The 5-point power fit's bias over the phase between two images (rms about its mean, in steps) at
// `phases` phases, and the curve's rises one and two images from the peak in the fit's transform (medians over
// the phase), as FocusCurveShape measures them on a stack.
struct CurveBias {
  double rms = 0.0, rise1 = 0.0, rise2 = 0.0;
};
template <class Blur>
CurveBias BiasOfCurve(Blur blur, int phases) {
  const std::vector<double> z = {0.0, 1.0, 2.0, 3.0, 4.0};
  std::vector<double> bias, one, two;
  for (int k = 0; k < phases; ++k) {
    const double t = (k + 0.5) / phases - 0.5;  // the surface t steps past image 2, the best
    std::array<double, 5> f;
    for (int i = 0; i < 5; ++i) f[std::size_t(i)] = std::pow(blur(std::abs((i - 2) - t)), -3.0);
    bias.push_back(imaging::PowerVertex(z, 2, f, 0.0, -2.0 / 3.0) - (2.0 + t));
    const auto p = [&](int i) { return std::pow(f[std::size_t(i)] / f[2], -2.0 / 3.0); };
    one.push_back(0.5 * (p(1) + p(3)) - 1.0), two.push_back(0.5 * (p(0) + p(4)) - 1.0);
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[(v.size() - 1) / 2] + v[v.size() / 2]);
  };
  double mean = 0.0, sum = 0.0;
  for (double b : bias) mean += b / phases;
  for (double b : bias) sum += (b - mean) * (b - mean);
  return {std::sqrt(sum / phases), median(one), median(two)};
}

TEST(FocusPhaseBias, PredictsTheFitsBiasFromTheRisesOfAFocusCurve) {
  // A blur that grows linearly from its diffraction floor (s = s0 + k |u|, NA 0.3 with a 0.8 um floor on 1 um
  // steps: k / s0 about 0.2) makes a V-topped transformed curve, which the 5-point parabola fits with a bias locked
  // to the phase; from its rises alone the prediction must find that bias, here computed at 997 phases from the
  // blur itself. The prediction's own grids (41 shares of V over round, 64 phases) leave 0.6-2.4 % here: held at 4 %.
  for (const double k : {0.1, 0.2, 0.4}) {
    const CurveBias truth = BiasOfCurve([k](double u) { return 1.0 + k * u; }, 997);
    const double predicted = imaging::PredictedPhaseBiasRms(truth.rise1, truth.rise2, -2.0 / 3.0);
    EXPECT_GT(truth.rms, 0.01) << k;  // a bias worth predicting
    EXPECT_NEAR(predicted, truth.rms, 0.04 * truth.rms) << k;
    std::printf("blur 1 + %.1f |u|: fit's phase bias %.4f step rms, predicted from the rises %.4f\n", k, truth.rms,
                predicted);
  }
  // A Gaussian beam's waist (s^2 = s0^2 + k^2 u^2) makes the transformed curve a parabola, which the fit follows
  // exactly: no bias to predict.
  const CurveBias waist = BiasOfCurve([](double u) { return std::sqrt(1.0 + 0.3 * u * u); }, 997);
  EXPECT_LT(waist.rms, 1e-6);
  EXPECT_LT(imaging::PredictedPhaseBiasRms(waist.rise1, waist.rise2, -2.0 / 3.0), 0.002);
  // Rises that describe no peak: nothing predicted.
  EXPECT_EQ(imaging::PredictedPhaseBiasRms(0.0, 0.5, -2.0 / 3.0), 0.0);
  EXPECT_EQ(imaging::PredictedPhaseBiasRms(0.5, 0.4, -2.0 / 3.0), 0.0);
}

}  // namespace
}  // namespace fvm

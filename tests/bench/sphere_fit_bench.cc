// Sphere fits of a 1-million-point calotte and calotte detection on a 4k x 4k height map, each against a
// baseline in the same run: PCL's RANSAC sphere model with its own refinement, and for detection the floor any
// detector pays (a least-squares plane, a threshold and OpenCV's connected components, no spheres).

#include <benchmark/benchmark.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_sphere.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/calotte_surface.h"
#include "imaging/calotte_detection.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {
namespace {

const Eigen::Vector3d kCentre(-154.5487, -115.4767, -50.3624);
constexpr double kRadius = 0.25;
constexpr double kSigma = 1e-4;  // 0.1 um height noise

// A 0.5 mm calotte seen up to 75 degrees of slope on a 0.42 um grid: 1.04 million heights, 0.1 um noise, and
// 0.5 % spikes of up to 20 um (the outliers a robust fit has to survive).
const std::vector<Eigen::Vector3d>& MillionPointCap() {
  static const std::vector<Eigen::Vector3d> points = [] {
    std::vector<Eigen::Vector3d> p;
    std::mt19937_64 rng(1);
    std::normal_distribution<double> noise(0.0, kSigma);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double pitch = 0.00042, reach = kRadius * std::sin(75 * M_PI / 180);
    const int n = static_cast<int>(reach / pitch) + 1;
    for (int iy = -n; iy <= n; ++iy) {
      for (int ix = -n; ix <= n; ++ix) {
        const double x = ix * pitch, y = iy * pitch;
        if (x * x + y * y > reach * reach) continue;
        double z = -std::sqrt(kRadius * kRadius - x * x - y * y) + noise(rng);
        if (uniform(rng) < 0.005) z += 0.02 * (2 * uniform(rng) - 1);
        p.emplace_back(kCentre.x() + x, kCentre.y() + y, kCentre.z() + z);
      }
    }
    return p;
  }();
  return points;
}

void FitBenchmark(benchmark::State& state, SphereFitOptions options) {
  const std::vector<Eigen::Vector3d>& points = MillionPointCap();
  SphereFit fit;
  for (auto _ : state) {
    fit = FitSphere(points, options);
    benchmark::DoNotOptimize(fit.centre_mm);
  }
  state.counters["points"] = static_cast<double>(points.size());
  state.counters["outliers"] = static_cast<double>(fit.points - fit.inliers);
  state.counters["centre_err_nm"] = (fit.centre_mm - kCentre).norm() * 1e6;
  state.counters["lm_iterations"] = fit.iterations;
  state.counters["trim_rounds"] = fit.trim_rounds;
}

void BM_SphereFit1M(benchmark::State& state) {
  SphereFitOptions options;  // orthogonal distances, trimming
  FitBenchmark(state, options);
}
BENCHMARK(BM_SphereFit1M)->Unit(benchmark::kMillisecond);

void BM_SphereFit1MHeightResidual(benchmark::State& state) {
  SphereFitOptions options;
  options.residual = SphereResidual::kHeight;
  FitBenchmark(state, options);
}
BENCHMARK(BM_SphereFit1MHeightResidual)->Unit(benchmark::kMillisecond);

void BM_SphereFit1MNoTrimming(benchmark::State& state) {
  SphereFitOptions options;
  options.outliers = SphereOutliers::kNone;
  FitBenchmark(state, options);
}
BENCHMARK(BM_SphereFit1MNoTrimming)->Unit(benchmark::kMillisecond);

// The same least squares through Ceres, one residual block per point: the reference our solver is tested
// against, and what the one-pass normal equations save.
void BM_SphereFit1MCeres(benchmark::State& state) {
  SphereFitOptions options;
  options.outliers = SphereOutliers::kNone;
  options.solver = SphereSolver::kCeres;
  FitBenchmark(state, options);
}
BENCHMARK(BM_SphereFit1MCeres)->Unit(benchmark::kMillisecond)->Iterations(1);

// Baseline: PCL's RANSAC with its sphere model (threshold 3 sigma + spikes' scale), then PCL's own refinement
// of the coefficients on the inliers (Levenberg-Marquardt with numeric derivatives). PCL works in float, so
// the points go in relative to their centroid; that costs the baseline nothing but the conversion.
void BM_PclRansacSphere1M(benchmark::State& state) {
  const std::vector<Eigen::Vector3d>& points = MillionPointCap();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : points) {
    const Eigen::Vector3d q = p - mean;
    cloud->push_back(pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
  }
  Eigen::VectorXf refined(4);
  std::size_t inliers = 0;
  for (auto _ : state) {
    pcl::SampleConsensusModelSphere<pcl::PointXYZ>::Ptr model(
        new pcl::SampleConsensusModelSphere<pcl::PointXYZ>(cloud));
    model->setRadiusLimits(0.5 * kRadius, 2 * kRadius);
    pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model);
    ransac.setDistanceThreshold(5 * kSigma);
    ransac.setMaxIterations(1000);
    ransac.computeModel();
    Eigen::VectorXf coefficients;
    ransac.getModelCoefficients(coefficients);
    pcl::Indices indices;
    ransac.getInliers(indices);
    model->optimizeModelCoefficients(indices, coefficients, refined);
    inliers = indices.size();
    benchmark::DoNotOptimize(refined);
  }
  const Eigen::Vector3d centre = mean + refined.head<3>().cast<double>();
  state.counters["points"] = static_cast<double>(points.size());
  state.counters["outliers"] = static_cast<double>(points.size() - inliers);
  state.counters["centre_err_nm"] = (centre - kCentre).norm() * 1e6;
}
BENCHMARK(BM_PclRansacSphere1M)->Unit(benchmark::kMillisecond);

// The 6 x 6 grid on 5.3 um pixels: a 4k x 4k map (16.7 million heights) with noise, dropouts, spikes and a tilt.
const artefacts::CalotteSurface& Grid4k() {
  static const artefacts::CalotteSurface surface = [] {
    artefacts::CalotteSurfaceOptions o;
    o.dx_mm = o.dy_mm = 0.0053;
    o.margin_mm = 0.5;
    o.rotation_rad = 0.5 * M_PI / 180;
    o.slope_x = 0.01;
    o.slope_y = -0.005;
    o.noise_sigma_mm = kSigma;
    o.missing_fraction = 0.05;
    o.spike_fraction = 0.001;
    o.spike_height_mm = 0.02;
    o.seed = 3;
    return artefacts::RenderCalotteSurface(artefacts::CalotteGrid6x6(), o);
  }();
  return surface;
}

void BM_DetectCalottes4k(benchmark::State& state) {
  const artefacts::CalotteSurface& surface = Grid4k();
  CalotteDetection detection;
  for (auto _ : state) {
    detection = DetectCalottes(surface.map);
    benchmark::DoNotOptimize(detection.calottes.data());
  }
  double worst = 0;
  for (const auto& c : detection.calottes) {
    double nearest = 1e9;
    for (const auto& t : surface.truth) nearest = std::min(nearest, (c.fit.centre_mm - t.centre).norm());
    worst = std::max(worst, nearest);
  }
  state.counters["megapixels"] = surface.map.size_x * static_cast<double>(surface.map.size_y) * 1e-6;
  state.counters["found"] = static_cast<double>(detection.calottes.size());
  state.counters["worst_err_nm"] = worst * 1e6;
}
BENCHMARK(BM_DetectCalottes4k)->Unit(benchmark::kMillisecond);

// Baseline: what every detector pays at least: a least-squares plane through all valid heights, a depth
// threshold and OpenCV's connected components, with no robust face, no screening and no spheres.
void BM_LevelAndLabel4kBaseline(benchmark::State& state) {
  const HeightMap& map = Grid4k().map;
  int components = 0;
  for (auto _ : state) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (int iy = 0; iy < map.size_y; ++iy) {
      for (int ix = 0; ix < map.size_x; ++ix) {
        const float z = map.at(ix, iy);
        if (!std::isfinite(z)) continue;
        const Eigen::Vector3d a(1.0, ix, iy);
        ata += a * a.transpose();
        atb += a * z;
      }
    }
    const Eigen::Vector3d plane = ata.ldlt().solve(atb);
    cv::Mat mask(map.size_y, map.size_x, CV_8U);
    for (int iy = 0; iy < map.size_y; ++iy) {
      auto* row = mask.ptr<std::uint8_t>(iy);
      for (int ix = 0; ix < map.size_x; ++ix) {
        const float z = map.at(ix, iy);
        row[ix] = std::isfinite(z) && plane[0] + plane[1] * ix + plane[2] * iy - z > 0.005 ? 255 : 0;
      }
    }
    cv::Mat labels, stats, centroids;
    components = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S) - 1;
    benchmark::DoNotOptimize(components);
  }
  state.counters["components"] = components;
}
BENCHMARK(BM_LevelAndLabel4kBaseline)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fvm::imaging

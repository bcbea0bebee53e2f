#include "imaging/io/sensofar_plu.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "PLU is little-endian and is copied as it is");

constexpr std::size_t kPluDateSize = 128;
constexpr std::size_t kPluCalibrationAt = kPluDateSize + 4 + 256;  // after the date, its time and the comment
constexpr std::size_t kPluMeasurementAt = kPluCalibrationAt + 40;
constexpr std::size_t kPluDataAt = kPluMeasurementAt + 72;
constexpr float kPluNotMeasured = 1000001.0f;
constexpr std::size_t kPluLayersAt = kPluMeasurementAt + 61;  // num_layers, a byte (0 in the oldest files: one)
constexpr std::size_t kPluLayerTail = 8;  // each layer's lowest and highest height (float32), before what follows
constexpr const char* kPluReexport = "the file is damaged or incomplete: export it from the instrument again";

}  // namespace

HeightMap ParseSensofarPlu(const std::string& bytes, const std::string& name) {
  if (bytes.size() < kPluDataAt + 8) {
    FailReading(name, "holds " + std::to_string(bytes.size()) + " bytes, fewer than the " +
                          std::to_string(kPluDataAt + 8) + " of a Sensofar PLU header; " + kPluReexport);
  }
  const char* p = bytes.data();
  const std::string date = FixedText(p, kPluDateSize);
  const float mppx = std::fabs(LoadBytes<float>(p + kPluCalibrationAt + 16));
  const float mppy = std::fabs(LoadBytes<float>(p + kPluCalibrationAt + 20));
  const std::uint32_t type = LoadBytes<std::uint32_t>(p + kPluMeasurementAt);
  if (type == 1 || type == 2 || type == 5) {
    FailReading(name, "holds a profile (measurement type " + std::to_string(type) +
                          "), not a surface; fvm reads PLU topographies and images (types 3 and 0)");
  }
  if (type != 0 && type != 3) {
    FailReading(name, "measurement type " + std::to_string(type) +
                          " is not one of PLU's topography (3) or image (0); " + kPluReexport);
  }
  const std::uint64_t rows = LoadBytes<std::uint32_t>(p + kPluDataAt);
  const std::uint64_t cols = LoadBytes<std::uint32_t>(p + kPluDataAt + 4);
  RequireGridSize(name, "the data block says", cols, rows, kPluReexport);
  const std::uint64_t n = rows * cols;
  const std::uint64_t heights_at = kPluDataAt + 8;
  if (bytes.size() - heights_at < n * sizeof(float)) {
    FailReading(name, "the data block says " + std::to_string(cols) + " x " + std::to_string(rows) + " heights (" +
                          std::to_string(n * sizeof(float)) + " bytes) but " +
                          std::to_string(bytes.size() - heights_at) + " bytes follow; " + kPluReexport);
  }
  if (!(mppx > 0.0f) || !(mppy > 0.0f) || !std::isfinite(mppx) || !std::isfinite(mppy)) {
    FailReading(name, "the pixel sizes mppx, mppy (" + FormatShortest(mppx) + ", " + FormatShortest(mppy) +
                          " um) are not positive; " + kPluReexport);
  }

  HeightMap map;
  map.size_x = static_cast<int>(cols);
  map.size_y = static_cast<int>(rows);
  map.dx_mm = static_cast<double>(mppx) / kMmPerMetre;  // micrometres to mm
  map.dy_mm = static_cast<double>(mppy) / kMmPerMetre;
  map.source = "Sensofar PLU" + (date.empty() ? std::string() : ", " + date);
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float z_um = LoadBytes<float>(p + heights_at + i * sizeof(float));
    map.z_mm[i] = (z_um == kPluNotMeasured || !std::isfinite(z_um)) ? std::numeric_limits<double>::quiet_NaN()
                                                                    : static_cast<double>(z_um) / kMmPerMetre;
  }
  // A multi-layer measurement (num_layers > 1: film thickness, a surface and the interfaces under it) stores each
  // layer as rows, columns, heights and their range, one after another (Pastewka's SurfaceTopography, PLUReader):
  // the first layer is the surface read here; the colour image follows the last layer.
  const int layers = std::max(1, static_cast<int>(static_cast<unsigned char>(p[kPluLayersAt])));
  std::uint64_t after = heights_at + n * sizeof(float) + kPluLayerTail;
  for (int layer = 1; layer < layers && after <= bytes.size(); ++layer) {
    if (bytes.size() - after < 8) {
      after = bytes.size() + 1;
      break;
    }
    const std::uint64_t layer_points = static_cast<std::uint64_t>(LoadBytes<std::uint32_t>(p + after)) *
                                       LoadBytes<std::uint32_t>(p + after + 4);
    if (layer_points > bytes.size() / sizeof(float)) {  // a layer the file cannot hold: no colour image found
      after = bytes.size() + 1;
      break;
    }
    after += 8 + layer_points * sizeof(float) + kPluLayerTail;
  }
  if (layers > 1) {
    map.notes.push_back("it holds " + std::to_string(layers) + " layers (a multi-layer measurement); the first, the "
                        "surface, is read");
  }
  if (after <= bytes.size() && bytes.size() - after >= 3 * n) {
    map.intensity.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto* rgb = reinterpret_cast<const unsigned char*>(p + after + 3 * i);
      map.intensity[i] = static_cast<float>(rgb[0] + rgb[1] + rgb[2]) / 3.0f;
    }
  }
  return map;
}

HeightMap ReadSensofarPlu(const std::filesystem::path& path) {
  return ParseSensofarPlu(ReadFileBytes(path), path.string());
}

}  // namespace fvm::imaging

#include "imaging/io/zygo_datx.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/datx_codec.h"
#include "imaging/io/plugin_loader.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr std::string_view kHdf5Signature("\x89HDF\r\n\x1a\n", 8);
constexpr const char* kDatxReexport = "the file is damaged or incomplete: save it from Mx again";
// A compressed dataset may hold far more values than its file has bytes; beyond 4096 values a byte (and 8 M values)
// a damaged header is more likely than a real map, which must not make fvm allocate gigabytes.
constexpr std::uint64_t kDatxValuesPerFileByte = 4096;
constexpr std::uint64_t kDatxAlwaysAllowed = std::uint64_t{1} << 23;

// Metres per unit of the heights, for the length units Mx writes.
std::optional<double> MetresPerUnit(const std::string& unit) {
  if (unit == "Meters") return 1.0;
  if (unit == "MilliMeters") return 1e-3;
  if (unit == "MicroMeters") return 1e-6;
  if (unit == "NanoMeters") return 1e-9;
  if (unit == "Angstroms") return 1e-10;
  return std::nullopt;
}

// The first value of a numeric attribute, or nullopt.
std::optional<double> FirstNumber(const DatxDataset& dataset, const std::string& attribute) {
  const auto found = dataset.numbers.find(attribute);
  if (found == dataset.numbers.end() || found->second.empty()) return std::nullopt;
  return found->second.front();
}

double PositiveNumber(const DatxDataset& dataset, const std::string& attribute, const std::string& name,
                      const std::string& why) {
  const std::optional<double> value = FirstNumber(dataset, attribute);
  if (!value || !(*value > 0.0) || !std::isfinite(*value)) {
    FailReading(name, dataset.path + " has no positive attribute '" + attribute + "' (" +
                          (value ? FormatShortest(*value) : std::string("absent")) + "), which " + why + "; " +
                          kDatxReexport);
  }
  return *value;
}

// The heights' metres per stored value.
double MetresPerValue(const DatxDataset& surface, const std::string& name) {
  const auto unit = surface.texts.find("Unit");
  if (unit == surface.texts.end()) {
    FailReading(name, surface.path + " has no 'Unit' attribute: the heights' unit is unknown; " + kDatxReexport);
  }
  if (const std::optional<double> metres = MetresPerUnit(unit->second)) return *metres;
  if (unit->second == "Fringes") {
    const std::string why = "makes metres of fringes";
    return PositiveNumber(surface, "Wavelength", name, why) *
           PositiveNumber(surface, "Interferometric Scale Factor", name, why) *
           PositiveNumber(surface, "Obliquity Factor", name, why);
  }
  FailReading(name, surface.path + " has heights in '" + QuotedForMessage(unit->second) +
                        "'; fvm reads Meters, MilliMeters, MicroMeters, NanoMeters, Angstroms and Fringes");
}

// Metres per pixel along one axis: Parameters[1] of its converter.
double PixelMetres(const DatxDataset& surface, const std::string& converter, const std::string& name) {
  const auto found = surface.converters.find(converter);
  const double pixel = found != surface.converters.end() && found->second.parameters.size() >= 2
                           ? found->second.parameters[1]
                           : std::numeric_limits<double>::quiet_NaN();
  if (!(pixel > 0.0) || !std::isfinite(pixel)) {
    FailReading(name, surface.path + " '" + converter + "' gives no positive pixel size (" + FormatShortest(pixel) +
                          " m): the measurement was saved without a lateral calibration; calibrate the objective "
                          "in Mx and save it again");
  }
  return pixel;
}

}  // namespace

bool HasHdf5Signature(const std::string& head) { return std::string_view(head).substr(0, 8) == kHdf5Signature; }

const DatxCodec& LoadDatxCodec(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_datx_hdf5.so", "fvm_datx_codec_v1", "HDF5", "libhdf5-103-1"};
  return *static_cast<const DatxCodec*>(LoadPlugin(kPlugin, action));
}

HeightMap ParseZygoDatx(const std::string& bytes, const std::string& name) {
  if (!HasHdf5Signature(bytes)) {
    FailReading(name, "does not start with HDF5's signature: not a Zygo DATX file");
  }
  const std::uint64_t max_points =
      std::min<std::uint64_t>(kMaxPoints, std::max(kDatxAlwaysAllowed, kDatxValuesPerFileByte * bytes.size()));
  DatxContent content;
  std::string error;
  if (!LoadDatxCodec("reading " + name).read(bytes, max_points, &content, &error)) {
    FailReading(name, error + "; " + kDatxReexport);
  }
  const DatxDataset& surface = content.surface;
  RequireGridSize(name, surface.path + " says", surface.cols, surface.rows, kDatxReexport);
  const double mm_per_value = MetresPerValue(surface, name) * kMmPerMetre;
  const std::optional<double> no_data = FirstNumber(surface, "No Data");

  HeightMap map;
  map.size_x = static_cast<int>(surface.cols);
  map.size_y = static_cast<int>(surface.rows);
  map.dx_mm = PixelMetres(surface, "X Converter", name) * kMmPerMetre;
  map.dy_mm = PixelMetres(surface, "Y Converter", name) * kMmPerMetre;
  map.source = "Zygo DATX " + surface.path + " (" + surface.type_name + ")";
  map.z_mm.resize(surface.values.size());
  for (std::size_t i = 0; i < surface.values.size(); ++i) {
    const double value = surface.values[i];
    const bool invalid = !std::isfinite(value) || (no_data && value == *no_data);
    map.z_mm[i] = invalid ? std::numeric_limits<double>::quiet_NaN() : value * mm_per_value;
  }
  if (content.intensity) {
    const DatxDataset& intensity = *content.intensity;
    if (intensity.rows == surface.rows && intensity.cols == surface.cols) {
      map.intensity.assign(intensity.values.begin(), intensity.values.end());
    } else {
      map.notes.push_back("its intensity (" + intensity.path + ", " + std::to_string(intensity.cols) + " x " +
                          std::to_string(intensity.rows) + ") is not on the heights' grid: left out");
    }
  }
  return map;
}

HeightMap ReadZygoDatx(const std::filesystem::path& path) { return ParseZygoDatx(ReadFileBytes(path), path.string()); }

}  // namespace fvm::imaging

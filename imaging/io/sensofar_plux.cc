#include "imaging/io/sensofar_plux.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <pugixml.hpp>
#include <string_view>
#include <utility>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"
#include "imaging/io/zip_archive.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "PLUx heights are little-endian and are copied as they are");

constexpr std::size_t kPluxLargestIndex = std::size_t{1} << 24;
constexpr const char* kPluxReexport = "the file is damaged or incomplete: export it from SensoSCAN again";

std::string PluxText(const pugi::xml_node& parent, const char* element) {
  return std::string(TrimBlanks(parent.child(element).text().get()));
}

double PluxNumber(const std::string& name, const pugi::xml_node& general, const char* element) {
  const std::string text = PluxText(general, element);
  const std::optional<double> value = ParseDouble(text);
  if (!value || !std::isfinite(*value)) {
    FailReading(name, "index.xml <GENERAL/" + std::string(element) + "> is '" + QuotedForMessage(text) +
                          "', not a number; " + kPluxReexport);
  }
  return *value;
}

}  // namespace

HeightMap ParseSensofarPlux(std::string bytes, const std::string& name) {
  const ZipReader zip(std::move(bytes), name);
  if (!zip.Has("index.xml")) FailReading(name, "the archive has no index.xml: not a Sensofar PLUx file");
  const std::string xml = zip.Read("index.xml", kPluxLargestIndex);
  pugi::xml_document document;
  if (const pugi::xml_parse_result parsed = document.load_buffer(xml.data(), xml.size()); !parsed) {
    FailReading(name, std::string("index.xml is not well-formed XML (") + parsed.description() + "); " + kPluxReexport);
  }
  const pugi::xml_node root = document.document_element();
  const pugi::xml_node general = root.child("GENERAL");
  if (!general) FailReading(name, "index.xml has no <GENERAL> element; " + std::string(kPluxReexport));
  const std::optional<std::int64_t> cols = ParseInt(PluxText(general, "IMAGE_SIZE_X"));
  const std::optional<std::int64_t> rows = ParseInt(PluxText(general, "IMAGE_SIZE_Y"));
  if (!cols || !rows || *cols < 1 || *rows < 1 ||
      static_cast<std::uint64_t>(*cols) * static_cast<std::uint64_t>(*rows) > kMaxPoints) {
    FailReading(name, "index.xml <GENERAL/IMAGE_SIZE_X> x <IMAGE_SIZE_Y> ('" + PluxText(general, "IMAGE_SIZE_X") +
                          "' x '" + PluxText(general, "IMAGE_SIZE_Y") + "') is not a grid fvm can hold; " +
                          kPluxReexport);
  }
  const double dx_um = std::fabs(PluxNumber(name, general, "FOV_X"));
  const double dy_um = std::fabs(PluxNumber(name, general, "FOV_Y"));
  if (!(dx_um > 0.0) || !(dy_um > 0.0)) {
    FailReading(name,
                "index.xml <GENERAL/FOV_X>, <FOV_Y> (the pixel sizes) are not positive; " + std::string(kPluxReexport));
  }
  std::string height_file;
  for (pugi::xml_node layer = root.first_child(); layer && height_file.empty(); layer = layer.next_sibling()) {
    if (std::string_view(layer.name()).starts_with("LAYER_")) height_file = PluxText(layer, "FILENAME_Z");
  }
  if (height_file.empty())
    FailReading(name, "index.xml names no height layer (<LAYER_n>/<FILENAME_Z>); " + std::string(kPluxReexport));
  if (!zip.Has(height_file))
    FailReading(name, "index.xml names the heights '" + height_file + "', which the archive lacks");
  const std::size_t n = static_cast<std::size_t>(*cols) * static_cast<std::size_t>(*rows);
  if (zip.DeclaredSize(height_file) != 4 * n) {
    FailReading(name, std::to_string(*cols) + " x " + std::to_string(*rows) + " float32 heights need " +
                          std::to_string(4 * n) + " bytes, but " + height_file + " holds " +
                          std::to_string(zip.DeclaredSize(height_file)) + "; " + kPluxReexport);
  }
  const std::string heights = zip.Read(height_file, 4 * n);

  HeightMap map;
  map.size_x = static_cast<int>(*cols);
  map.size_y = static_cast<int>(*rows);
  map.dx_mm = dx_um / kMmPerMetre;
  map.dy_mm = dy_um / kMmPerMetre;
  map.source = "Sensofar PLUx";
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float z_um = LoadBytes<float>(heights.data() + 4 * i);
    map.z_mm[i] =
        std::isfinite(z_um) ? static_cast<double>(z_um) / kMmPerMetre : std::numeric_limits<double>::quiet_NaN();
  }
  return map;
}

HeightMap ReadSensofarPlux(const std::filesystem::path& path) {
  return ParseSensofarPlux(ReadFileBytes(path), path.string());
}

}  // namespace fvm::imaging

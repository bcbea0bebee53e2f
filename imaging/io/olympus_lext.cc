#include "imaging/io/olympus_lext.h"

#include <pugixml.hpp>

#include <cctype>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/image_codec.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr int kLextMostPages = 64;
constexpr double kLextMmPerPicometre = 1e-9;
constexpr const char* kLextReexport = "the file is damaged or incomplete: save it from the LEXT software again";

std::string UpperCase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// A positive number of picometres from the XML's HeightInfo, named in the refusal.
double Picometres(const pugi::xml_node& info, const char* field, const std::string& name) {
  const pugi::xml_node node = info.child(field);
  const std::optional<double> value = ParseDouble(TrimBlanks(node.text().get()));
  if (!node || !value || !(*value > 0.0) || !std::isfinite(*value)) {
    FailReading(name, "page 0's description has no positive HeightInfo/" + std::string(field) + " ('" +
                          QuotedForMessage(node.text().get()) + "'); " + kLextReexport);
  }
  return *value;
}

// One page's values as unsigned counts (the codec would scale integers read as floats to 0..1).
std::vector<std::uint32_t> ReadCounts(ImageFileReader& page, const std::string& name, const std::string& what,
                                      int width, int height) {
  const ImageHeader& header = page.Header();
  if (header.width != width || header.height != height || header.depth != 1 || header.channels != 1) {
    FailReading(name, "its " + what + " page is " + std::to_string(header.width) + " x " +
                          std::to_string(header.height) + " with " + std::to_string(header.channels) +
                          " channels, not " + std::to_string(width) + " x " + std::to_string(height) +
                          " with one; " + kLextReexport);
  }
  if (header.type != PixelType::kUint8 && header.type != PixelType::kUint16 && header.type != PixelType::kUint32) {
    FailReading(name, "its " + what + " page holds " + header.type_name + ", not unsigned counts; " + kLextReexport);
  }
  // In the page's own type: OpenImageIO rescales integers converted to a wider type.
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::uint32_t> counts(n);
  const auto read = [&](auto tag) {
    std::vector<decltype(tag)> raw(n);
    std::string error;
    if (!page.ReadPixels(0, 1, header.type, raw.data(), &error) || !error.empty()) {
      FailReading(name, "cannot read its " + what + " page (" + error + "); " + kLextReexport);
    }
    for (std::size_t i = 0; i < n; ++i) counts[i] = raw[i];
  };
  if (header.type == PixelType::kUint8) {
    read(std::uint8_t{});
  } else if (header.type == PixelType::kUint16) {
    read(std::uint16_t{});
  } else {
    read(std::uint32_t{});
  }
  return counts;
}

// The number of pages the TIFF's chain of directories links, each link checked to lie inside the file: libtiff ends
// a chain quietly at a link past the end, so a cut LEXT would lose its last pages (its INVALID page: invalid points
// read as heights) without a word.
int LinkedTiffPages(const std::string& bytes, const std::string& name) {
  if (bytes.size() < 8 || bytes.compare(0, 4, std::string("II*\0", 4)) != 0) {
    FailReading(name, "is not a little-endian TIFF (II*): not an Olympus LEXT file");
  }
  std::uint64_t at = LoadBytes<std::uint32_t>(bytes.data() + 4);
  int pages = 0;
  while (at != 0 && pages < kLextMostPages) {
    if (at > bytes.size() || bytes.size() - at < 2 ||
        bytes.size() - at - 2 < 12u * LoadBytes<std::uint16_t>(bytes.data() + at) + 4u) {
      FailReading(name, "its TIFF page " + std::to_string(pages) + " is linked at byte " + std::to_string(at) +
                            ", past the end of the file (" + std::to_string(bytes.size()) + " bytes); " +
                            kLextReexport);
    }
    const std::uint64_t entries = LoadBytes<std::uint16_t>(bytes.data() + at);
    at = LoadBytes<std::uint32_t>(bytes.data() + at + 2 + 12 * entries);
    ++pages;
  }
  return pages;
}

}  // namespace

HeightMap ReadOlympusLext(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::size_t file_bytes = CheckReadableFile(path);
  const int linked_pages = LinkedTiffPages(ReadFileBytes(path), name);
  const ImageCodec& codec = LoadImageCodec("reading " + name);
  std::string error;
  std::unique_ptr<ImageFileReader> first = codec.open_subimage(path, 0, &error);
  if (!first || first->Header().format_name != "tiff") {
    FailReading(name, "cannot read it as a TIFF (" + error + "): not an Olympus LEXT file");
  }
  const std::string description = first->Header().description;
  if (description.find("<TiffTagDescData") == std::string::npos) {
    FailReading(name, "page 0's ImageDescription is not LEXT's <TiffTagDescData> XML: not an Olympus LEXT file");
  }
  pugi::xml_document xml;
  const pugi::xml_parse_result parsed = xml.load_buffer(description.data(), description.size());
  if (!parsed) {
    FailReading(name, std::string("page 0's <TiffTagDescData> is not well-formed XML (") + parsed.description() +
                          "); " + kLextReexport);
  }
  const pugi::xml_node info = xml.child("TiffTagDescData").child("HeightInfo");
  if (!info) FailReading(name, "page 0's <TiffTagDescData> has no <HeightInfo>: a LEXT without heights");
  const double x_pm = Picometres(info, "HeightDataPerPixelX", name);
  const double y_pm = Picometres(info, "HeightDataPerPixelY", name);
  const double z_pm = Picometres(info, "HeightDataPerPixelZ", name);

  std::vector<std::unique_ptr<ImageFileReader>> pages;
  std::vector<std::string> titles;
  for (int page = 1; page < kLextMostPages; ++page) {
    std::unique_ptr<ImageFileReader> reader = codec.open_subimage(path, page, &error);
    if (!reader) break;
    CheckPixelsFitFile(path, reader->Header(), file_bytes);
    titles.push_back(UpperCase(FixedText(reader->Header().description.data(), reader->Header().description.size())));
    pages.push_back(std::move(reader));
  }
  if (static_cast<int>(pages.size()) + 1 != std::min(linked_pages, kLextMostPages)) {
    FailReading(name, "its TIFF links " + std::to_string(linked_pages) + " pages, but only " +
                          std::to_string(pages.size() + 1) + " can be read (" + error + "); " + kLextReexport);
  }
  const auto page_named = [&](const char* title) -> ImageFileReader* {
    for (std::size_t i = 0; i < pages.size(); ++i) {
      if (titles[i] == title) return pages[i].get();
    }
    return nullptr;
  };
  ImageFileReader* heights = page_named("HEIGHT");
  if (!heights) FailReading(name, "has no page named HEIGHT: a LEXT of images only");
  const ImageHeader& grid = heights->Header();
  RequireGridSize(name, "its HEIGHT page says", static_cast<std::uint64_t>(std::max(grid.width, 0)),
                  static_cast<std::uint64_t>(std::max(grid.height, 0)), kLextReexport);
  const std::vector<std::uint32_t> counts = ReadCounts(*heights, name, "HEIGHT", grid.width, grid.height);

  HeightMap map;
  map.size_x = grid.width;
  map.size_y = grid.height;
  map.dx_mm = x_pm * kLextMmPerPicometre;
  map.dy_mm = y_pm * kLextMmPerPicometre;
  map.source = "Olympus LEXT";
  map.z_mm.resize(counts.size());
  const double mm_per_count = z_pm * kLextMmPerPicometre;
  for (std::size_t i = 0; i < counts.size(); ++i) map.z_mm[i] = counts[i] * mm_per_count;
  if (ImageFileReader* invalid = page_named("INVALID")) {
    const std::vector<std::uint32_t> marks = ReadCounts(*invalid, name, "INVALID", grid.width, grid.height);
    for (std::size_t i = 0; i < marks.size(); ++i) {
      if (marks[i] != 0) map.z_mm[i] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  if (ImageFileReader* intensity = page_named("INTENSITY")) {
    const std::vector<std::uint32_t> grey = ReadCounts(*intensity, name, "INTENSITY", grid.width, grid.height);
    map.intensity.assign(grey.begin(), grey.end());
  }
  return map;
}

}  // namespace fvm::imaging

// X3P as it is found (imaging/io/x3p_archive.h): a file zipped by a desktop archiver around the folder it was
// unpacked into, with macOS clutter, its main.xml edited by an older writer (no namespace on the root, an empty
// <Offset/>), or carrying an annotation mask, reads to the same heights as the original, and fvm says what was
// unusual. Built from fvm's own X3P and, where ../shared is present, from the real MountainsMap X3P there.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/md5.h"
#include "imaging/io/x3p.h"
#include "imaging/io/zip_archive.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using testing::SampleMap;

const std::filesystem::path kRealX3p = std::filesystem::path(FVM_REALDATA_DIR) / "surfaces" / "x3p-2.x3p";

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The X3P's entries moved into `folder`, main.xml passed through `edit` (its checksum file rewritten to match,
// as the tool that edited it would), and the clutter a Mac's archiver adds.
std::string DesktopZipped(const std::string& x3p, const std::string& folder,
                          const std::function<std::string(std::string)>& edit) {
  const ZipReader zip(x3p, "original.x3p");
  std::vector<ZipEntry> entries;
  const std::string xml = edit(zip.Read("main.xml", 1 << 30));
  for (const std::string& name : zip.Entries()) {
    if (name.ends_with('/')) continue;
    std::string content = name == "main.xml" ? xml : zip.Read(name, 1 << 30);
    if (name == "md5checksum.hex") content = Md5Hex(xml) + " *main.xml\n";
    entries.push_back({folder + name, std::move(content)});
  }
  entries.push_back({"__MACOSX/" + folder + "._main.xml", std::string(82, '\x01')});
  entries.push_back({folder + ".DS_Store", std::string(64, '\0')});
  return BuildZip(entries);
}

bool HasNote(const HeightMap& map, const std::string& part) {
  return std::any_of(map.notes.begin(), map.notes.end(),
                     [&](const std::string& note) { return note.find(part) != std::string::npos; });
}

std::string AsFound(std::string xml) {
  xml = Replaced(xml, "<p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\"", "<ISO5436_2");
  xml = Replaced(xml, "</p:ISO5436_2>", "</ISO5436_2>");
  const std::size_t cx = xml.find("<CX>");
  const std::size_t offset = xml.find("<Offset>", cx);
  xml.replace(offset, xml.find("</Offset>", offset) + 9 - offset, "<Offset/>");
  return xml;
}

void ExpectReadsAsFound(const std::string& original) {
  HeightMap expected = ParseX3p(original, "original.x3p");
  expected.x0_mm = 0.0;  // the emptied <CX/Offset/> reads as its default, 0
  const HeightMap found = ParseX3p(DesktopZipped(original, "scan/", AsFound), "found.x3p");
  testing::ExpectSameHeights(expected, found);
  EXPECT_EQ(found.dx_mm, expected.dx_mm);
  EXPECT_EQ(found.x0_mm, 0.0);
  EXPECT_EQ(found.y0_mm, expected.y0_mm);
  EXPECT_TRUE(HasNote(found, "inside the folder 'scan/'"));
  EXPECT_TRUE(HasNote(found, "__MACOSX/"));
  EXPECT_TRUE(HasNote(found, "not in the ISO 5436-2 namespace"));
  EXPECT_TRUE(HasNote(found, "<Record1/Axes/CX/Offset> is empty"));
  EXPECT_TRUE(ParseX3p(original, "original.x3p").notes.empty());
}

TEST(X3pAsFound, DesktopZippedFolderReadsWithNotes) {
  X3pWriteOptions options;
  options.date = "2024-01-01T00:00:00+00:00";
  ExpectReadsAsFound(BuildX3p(SampleMap(9, 6), options));
}

TEST(X3pAsFound, RealMountainsMapFileZippedAroundItsFolder) {
  if (!std::filesystem::exists(kRealX3p)) GTEST_SKIP() << kRealX3p << " is absent (no ../shared)";
  ExpectReadsAsFound(ReadFileBytes(kRealX3p));
}

TEST(X3pAsFound, AnnotationMaskIsNotedNotApplied) {
  const std::string original = BuildX3p(SampleMap(5, 4));
  const auto with_mask = [](std::string xml) {
    return Replaced(xml, "</Record3>", "<Mask><Background>#cd7f32</Background></Mask></Record3>");
  };
  const ZipReader zip(DesktopZipped(original, "", with_mask), "masked.x3p");
  std::vector<ZipEntry> entries;
  for (const std::string& name : zip.Entries()) entries.push_back({name, zip.Read(name, 1 << 30)});
  entries.push_back({"bindata/mask.png", "\x89PNG not a real image"});
  const HeightMap masked = ParseX3p(BuildZip(entries), "masked.x3p");
  testing::ExpectSameHeights(ParseX3p(original, "original.x3p"), masked);
  EXPECT_TRUE(HasNote(masked, "annotation mask"));
}

TEST(X3pAsFound, TwoCandidateDescriptionsAreRefused) {
  const std::string one = BuildX3p(SampleMap(5, 4));
  const ZipReader zip(one, "one.x3p");
  std::vector<ZipEntry> entries;
  for (const std::string folder : {"a/", "b/"}) {
    for (const std::string& name : zip.Entries()) entries.push_back({folder + name, zip.Read(name, 1 << 30)});
  }
  try {
    ParseX3p(BuildZip(entries), "two.x3p");
    ADD_FAILURE() << "two X3P descriptions read without an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("two.x3p: the archive holds several X3P descriptions (a/main.xml"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace fvm::imaging

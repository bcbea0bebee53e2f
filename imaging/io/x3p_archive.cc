#include "imaging/io/x3p_archive.h"

#include <string_view>

#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr const char* kX3pNamespaceUri = "http://www.opengps.eu/2008/ISO5436_2";

bool IsArchiveClutter(std::string_view entry) {
  const std::size_t slash = entry.find_last_of('/', entry.size() > 1 ? entry.size() - 2 : 0);
  const std::string_view leaf = slash == std::string_view::npos ? entry : entry.substr(slash + 1);
  return entry.starts_with("__MACOSX/") || leaf == ".DS_Store" || leaf.starts_with("._") || leaf == "Thumbs.db";
}

std::string_view LocalNameOf(std::string_view full) {
  const std::size_t colon = full.find(':');
  return colon == std::string_view::npos ? full : full.substr(colon + 1);
}

}  // namespace

std::string X3pArchiveLayout::Entry(const ZipReader& zip, const std::string& path) const {
  if (folder.empty() || zip.Has(path)) return path;
  return folder + path;
}

X3pArchiveLayout LocateX3pMainXml(const ZipReader& zip, const std::string& name) {
  X3pArchiveLayout layout;
  int clutter = 0;
  std::vector<std::string> folders;  // top folders that hold a main.xml
  for (const std::string& entry : zip.Entries()) {
    if (entry.ends_with('/')) continue;  // a folder: nothing to read
    if (IsArchiveClutter(entry)) {
      ++clutter;
      continue;
    }
    const std::size_t slash = entry.find('/');
    if (slash != std::string::npos && slash + 1 < entry.size() && entry.substr(slash + 1) == "main.xml") {
      folders.push_back(entry.substr(0, slash + 1));
    }
  }
  if (!zip.Has("main.xml")) {
    if (folders.empty()) {
      FailReading(name, "the archive has no main.xml: not an X3P file (ISO 25178-72); export the surface as X3P");
    }
    if (folders.size() > 1) {
      FailReading(name, "the archive holds several X3P descriptions (" + folders[0] + "main.xml, " + folders[1] +
                            "main.xml ...): unpack it and give one X3P file at a time");
    }
    layout.folder = folders.front();
    layout.notes.push_back("main.xml is inside the folder '" + layout.folder +
                           "' (the X3P was zipped around its folder); read from there");
  }
  if (clutter > 0) {
    layout.notes.push_back("the archive holds " + std::to_string(clutter) +
                           " files a desktop archiver adds (__MACOSX/, .DS_Store); ignored");
  }
  return layout;
}

std::vector<std::string> X3pDocumentNotes(const pugi::xml_node& root, const ZipReader& zip,
                                          const X3pArchiveLayout& layout) {
  std::vector<std::string> notes;
  const std::string_view full = root.name();
  const std::size_t colon = full.find(':');
  const std::string attribute =
      colon == std::string_view::npos ? "xmlns" : "xmlns:" + std::string(full.substr(0, colon));
  if (std::string_view(root.attribute(attribute.c_str()).value()) != kX3pNamespaceUri) {
    notes.push_back("main.xml's root <" + std::string(full) +
                    "> is not in the ISO 5436-2 namespace (an older writer's form); read as ISO 25178-72");
  }
  bool mask = false;
  for (pugi::xml_node child = root.first_child(); child; child = child.next_sibling()) {
    mask = mask || LocalNameOf(child.name()) == "Mask";
    if (LocalNameOf(child.name()) != "Record3") continue;
    for (pugi::xml_node inner = child.first_child(); inner; inner = inner.next_sibling()) {
      mask = mask || LocalNameOf(inner.name()) == "Mask";
    }
  }
  if (mask || zip.Has(layout.Entry(zip, "bindata/mask.png"))) {
    notes.push_back(
        "it holds an annotation mask (bindata/mask.png, <Mask>): the heights are read, the mask's colours "
        "are not applied to them");
  }
  return notes;
}

}  // namespace fvm::imaging

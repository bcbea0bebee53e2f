#pragma once
// X3P as it is found, not only as ISO 25178-72 writes it: where main.xml sits in the archive and what about the
// archive and its description is unusual but unambiguous. A desktop archiver zips the folder an X3P was unpacked
// into ("scan/main.xml", "scan/bindata/data.bin") and adds its own clutter (macOS's "__MACOSX/" resource forks and
// ".DS_Store" files); older writers leave the root element without the ISO 5436-2 namespace; x3ptools (Hofmann
// 2017) and FiX3P add an annotation mask (bindata/mask.png, <Mask> in Record3). fvm reads through all of these and
// says what it found (HeightMap::notes), the way other X3P readers open them.

#include <pugixml.hpp>
#include <string>
#include <vector>

#include "imaging/io/zip_archive.h"

namespace fvm::imaging {

struct X3pArchiveLayout {
  std::string folder;  // "" or the one top folder holding main.xml, with its trailing '/'
  std::vector<std::string> notes;

  // The archive entry of a path that main.xml names (relative to the X3P's root): inside the folder when there.
  std::string Entry(const ZipReader& zip, const std::string& path) const;
};

// Throws InputError naming the file when the archive holds no main.xml, or several that could each be the X3P's.
X3pArchiveLayout LocateX3pMainXml(const ZipReader& zip, const std::string& name);

// Notes about main.xml itself: a root without the ISO 5436-2 namespace, an annotation mask.
std::vector<std::string> X3pDocumentNotes(const pugi::xml_node& root, const ZipReader& zip,
                                          const X3pArchiveLayout& layout);

}  // namespace fvm::imaging

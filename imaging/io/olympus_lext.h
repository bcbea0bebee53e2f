#pragma once
// Olympus LEXT, the export of Olympus' OLS4000/OLS4100/OLS4500 laser confocal microscopes, as Gwyddion's
// lextfile.c (Necas and Klapetek 2010) reads it. No instrument file was at hand: the reader follows that description
// and is tested on files written the same way (tests/support/lext_files.h). A LEXT is a multi-page TIFF:
//   page 0: the colour image, its ImageDescription an XML document <TiffTagDescData ...> whose
//     HeightInfo/HeightDataPerPixelX, ...Y and ...Z give the pixel and the height per count in picometres;
//   the other pages, each named by its ImageDescription: HEIGHT (unsigned counts), INTENSITY (the laser's grey
//     levels), COLOR, THUMBNAIL and INVALID (one bit per point).
// Heights are HEIGHT's counts times HeightDataPerPixelZ; INTENSITY is the intensity. Points set in INVALID are taken
// as invalid (Gwyddion leaves that page unread; the reading follows its name, unconfirmed by an instrument file).
// Recognised by the extension .lext (its content is a TIFF). The pages are read through the image plugin
// (OpenImageIO, imaging/io/image_codec.h).

#include <filesystem>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the page or field for anything wrong with it.
HeightMap ReadOlympusLext(const std::filesystem::path& path);

}  // namespace fvm::imaging

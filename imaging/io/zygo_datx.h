#pragma once
// Zygo DATX, the HDF5 export of Zygo's Mx software (NewView, Nexview, ZeGage, Verifire), as Pastewka's
// SurfaceTopography (2023, DATXReader), prysm (Dube 2019, read_zygo_datx) and Zygo's own layout notes describe it.
// No instrument file was at hand: the reader follows those descriptions and is tested on files written the same way
// (tests/support/datx_files.h). The file is HDF5 (signature "\x89HDF\r\n\x1a\n"):
//   the heights: the first dataset of the group /Data/Surface (Mx), else the dataset /Measurement/Surface (Nexview
//     NX2), two-dimensional, rows of the image one after another, any numeric type;
//   its attributes: "Unit" (the heights' unit: Meters, MilliMeters, MicroMeters, NanoMeters, Angstroms, or Fringes
//     with "Wavelength" in metres, "Interferometric Scale Factor" and "Obliquity Factor" making metres of them),
//     "No Data" (the value of an invalid point; NaN and infinities are invalid too), "X Converter" and
//     "Y Converter" (compound: Category, BaseUnit, Parameters; Parameters[1] is the pixel in metres);
//   the intensity, if any: the first dataset of /Data/Intensity (or /Measurement/Intensity) on the same grid.
// HDF5 is read by a plugin (imaging/io/datx_codec.h), so that commands which never meet a DATX do not load it.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the field for anything wrong with it.
HeightMap ReadZygoDatx(const std::filesystem::path& path);
HeightMap ParseZygoDatx(const std::string& bytes, const std::string& name);
// True when `head` starts with HDF5's signature.
bool HasHdf5Signature(const std::string& head);

}  // namespace fvm::imaging

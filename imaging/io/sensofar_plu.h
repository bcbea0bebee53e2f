#pragma once
// Sensofar PLU, the native export of Sensofar's PLu and S neox confocal, interferometric and focus-variation
// profilers (and of Leica's DCM 3D, built on them). Layout as Gwyddion's reader (sensofar.c, Necas and Horak 2008)
// reads it, little-endian throughout:
//   a 128-byte date text ("Mon Apr 19 11:40:13 2021"), a uint32 time, a 256-byte comment;
//   the axes calibration: uint32 rows, uint32 columns, uint32 N_tall, then float32 dy_multip, mppx, mppy (the pixel
//   sizes, micrometres), x_0, y_0, mpp_tall, z_0;
//   the measurement configuration: uint32 type (0 image, 3 topography; 1, 2 and 5 are profiles), ... 72 bytes;
//   the data: uint32 rows, uint32 columns, then rows x columns float32 heights in micrometres, row by row, where
//   1000001 marks a point not measured.
// Newer files (S neox) follow the heights with 8 bytes and the colour image as R, G, B bytes per point: the
// intensity image (the mean of the three). Gwyddion 2.62 reads it as "Gray".

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the field for anything wrong with it.
HeightMap ReadSensofarPlu(const std::filesystem::path& path);
HeightMap ParseSensofarPlu(const std::string& bytes, const std::string& name);

}  // namespace fvm::imaging

#pragma once
// PLY files (ascii, binary_little_endian, binary_big_endian) read by fvm itself: the x, y, z of the vertex
// element, every other element checked and skipped.
//
// Why not PCL's PLYReader: like its PCD reader it trusts the header, and a damaged count or list length sends it
// past the end of its buffers (issue 19). The format is small enough that reading it whole, with every count
// checked against the bytes that are really there, is less code than validating it for PCL first, and one
// parser is one behaviour. What PCL's PLYWriter adds for organised clouds is understood: `obj_info num_cols` /
// `num_rows` give the grid, and a `range_grid` element (one list per grid point, empty where the point is
// missing) places the vertices on it, with NaN for the missing ones.

#include <string>
#include <string_view>

#include "imaging/point_cloud.h"

namespace fvm::imaging {

// The vertices of the PLY file `bytes` (x, y, z of any numeric type), times mm_per_unit. Throws InputError
// naming `name`, the header line or the element and row, and what is wrong, for anything the format does not
// allow or when the body holds more or fewer bytes than the header declares.
PointCloud ParsePly(std::string_view bytes, const std::string& name, double mm_per_unit = 1.0);

}  // namespace fvm::imaging

#pragma once
// PCD files (PCL's point-cloud format, versions 0.5 to 0.7) read by fvm itself: DATA ascii, binary and
// binary_compressed (LZF).
//
// Why not PCL's PCDReader: it trusts the header (issue 19). A first line of one blank crashed it; a
// binary_compressed body with zero sizes crashed it; COUNT 1000000 took 16 s and 4 GB and read every
// coordinate as 0; rows with fewer values than FIELDS x COUNT read as zeros. Validating a file whole before
// PCL sees it needs every header field, the body size against COUNT x SIZE x POINTS, the compressed sizes and
// every ascii row checked: that is already a reader, and taking x, y, z out of it is a few lines more. One
// parser is also one behaviour, it is as fast (one pass, no intermediate PCLPointCloud2 copy) and it needs no
// PCL at run time.
//
// Strict on purpose: every value the header promises must be there, and nothing more, because a file whose
// header and body disagree would otherwise read as made-up numbers.

#include <string>
#include <string_view>

#include "imaging/point_cloud.h"

namespace fvm::imaging {

// The x, y and z fields of the PCD file `bytes` (any numeric TYPE and SIZE, COUNT 1; other fields are checked
// and skipped), times mm_per_unit. WIDTH x HEIGHT stays the cloud's grid. Throws InputError naming `name`, the
// header line or data row, and what is wrong, for anything the format does not allow.
PointCloud ParsePcd(std::string_view bytes, const std::string& name, double mm_per_unit = 1.0);

}  // namespace fvm::imaging

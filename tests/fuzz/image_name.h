#pragma once
// Image readers open a path and OpenImageIO picks the decoder by the extension: name the scratch file after the
// bytes' signature, so that PNG seeds reach the PNG decoder and everything else the TIFF one.

#include <string>
#include <string_view>

namespace fvm::fuzz {

inline std::string ImageName(std::string_view bytes, const std::string& stem) {
  return stem + (bytes.substr(0, 4) == "\x89PNG" ? ".png" : ".tif");
}

}  // namespace fvm::fuzz

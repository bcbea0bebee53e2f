#pragma once
// MD5 digests as X3P containers carry them [ISO 25178-72]: for detecting corruption, not for security.

#include <string>
#include <string_view>

namespace fvm::imaging {

// 32 lowercase hexadecimal digits.
std::string Md5Hex(std::string_view bytes);

}  // namespace fvm::imaging

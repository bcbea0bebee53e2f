#include "imaging/io/md5.h"

#include <openssl/evp.h>

#include <array>
#include <stdexcept>

namespace fvm::imaging {

std::string Md5Hex(std::string_view bytes) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  // EVP_Digest fails only when the crypto library is broken (no MD5 provider): not the user's doing.
  if (EVP_Digest(bytes.data(), bytes.size(), digest.data(), &length, EVP_md5(), nullptr) != 1 || length != 16) {
    throw std::runtime_error("OpenSSL cannot compute MD5 digests (is the default provider available?)");
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * length);
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 0xf];
  }
  return hex;
}

}  // namespace fvm::imaging

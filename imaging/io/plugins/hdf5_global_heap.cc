#include "imaging/io/plugins/hdf5_global_heap.h"

#include <cstdint>
#include <cstring>
#include <string_view>

namespace fvm::imaging {
namespace {

constexpr std::size_t kCollectionHeader = 16;  // "GCOL", version, 3 reserved, 8-byte size
constexpr std::size_t kObjectHeader = 16;      // index, references, reserved, 8-byte size
constexpr std::uint64_t kSmallestCollection = 4096;

std::uint64_t LittleEndian(const char* p, int bytes) {
  std::uint64_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(p[i]);
  return value;
}

// What is wrong with the collection of `size` bytes at `at`, or empty.
std::string WalkCollection(const std::string& bytes, std::size_t at, std::uint64_t size) {
  const std::string where = "the global heap collection at byte " + std::to_string(at);
  std::uint64_t offset = kCollectionHeader;
  while (offset < size) {
    if (size - offset < kObjectHeader) return {};  // too small for an object: free space, as HDF5 takes it
    const char* object = bytes.data() + at + offset;
    const std::uint64_t index = LittleEndian(object, 2);
    const std::uint64_t object_size = LittleEndian(object + 8, 8);
    if (object_size > size - offset) {
      return where + ": object " + std::to_string(index) + " says " + std::to_string(object_size) +
             " bytes, more than the collection's " + std::to_string(size - offset) + " left";
    }
    // The free space (index 0) counts its own header; every other object adds it and pads its data to 8 bytes.
    const std::uint64_t need = index == 0 ? object_size : kObjectHeader + (object_size + 7) / 8 * 8;
    if (need == 0) return where + ": its free space has size 0 (HDF5 would walk it for ever)";
    if (need > size - offset) {
      return where + ": object " + std::to_string(index) + " runs past the collection's end";
    }
    offset += need;
  }
  return {};
}

}  // namespace

std::string DamagedGlobalHeap(const std::string& bytes) {
  const std::string_view view(bytes);
  for (std::size_t at = view.find("GCOL"); at != std::string_view::npos; at = view.find("GCOL", at + 1)) {
    if (bytes.size() - at < kCollectionHeader || bytes[at + 4] != 1) continue;
    const std::uint64_t size = LittleEndian(bytes.data() + at + 8, 8);
    if (size < kSmallestCollection || size > bytes.size() - at) continue;  // not a collection HDF5 would load
    if (std::string damaged = WalkCollection(bytes, at, size); !damaged.empty()) return damaged;
  }
  return {};
}

}  // namespace fvm::imaging
